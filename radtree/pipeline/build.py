"""Build folders: ``PROJECT/build/<scenario>/`` (or ``<scenario>@k`` per crown realisation).

Each holds the scene as the folder engine (Radiance) writes it — ``materials.rad``,
``geometry/``, ``skies/``, ``grids/*.pts``, a Makefile per hour — plus ``model.png`` (in the
first crown realisation only: the one the report shows), ``scene.pickle`` (radtree's own
in-memory scene: ``simulate`` and ``report`` load it instead of building the crowns again,
:func:`built_scene`) and a ``manifest.json`` carrying the scenario's parameter hash and every
file's checksum, by which a stale folder is detected; ``build/Makefile`` runs them all.
"""

from __future__ import annotations

import json
import logging
import multiprocessing
import pickle
import shutil
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

import radtree
from radtree.config import Project, Scenario, effective_project
from radtree.engines.registry import folder_engine
from radtree.errors import RadtreeError
from radtree.fileio import atomic_dir, write_text
from radtree.light.hours import hour_states
from radtree.log import progress
from radtree.pipeline.assemble import BuiltScene, facade_frame, make_scene
from radtree.pipeline.manifest import file_sha256, manifest
from radtree.pipeline.processes import usable_cores
from radtree.pipeline.realisations import (
    REALISATION_MARK,
    is_later_realisation,
    parent_name,
    realisations_of,
    selected,
)

log = logging.getLogger(__name__)


def hour_grids(project: Project, time_: str, available: list[str],
               wanted: list[str] | None, sc: Scenario | None = None) -> list[str]:
    """Grids to trace at an hour: the dense façade maps only at ``sensors.dense_hours``, and
    only in the first crown realisation (``F@1``) of a scenario with several."""
    from radtree.sensor_grid import is_dense_grid

    use = [g for g in available if wanted is None or g in wanted]
    dense = project.sensors.dense_hours
    if (dense and time_ not in dense) or (sc is not None and is_later_realisation(sc.name)):
        use = [g for g in use if not is_dense_grid(g)]
    return use


def log_notes(name: str, notes: list[str]) -> None:
    """Log the notes a user must see at build time: the crown–wall policy's clip note
    (:mod:`radtree.trees.wall_policy`) and where an inventory's façade was placed
    (:mod:`radtree.site.placement`)."""
    from radtree.site.placement import NOTE_PREFIX as PLACED
    from radtree.trees.wall_policy import NOTE_PREFIX as WALL

    for note in notes:
        if note.startswith((WALL, PLACED)):
            log.info("  %s: %s", name, note)


def build_project(project: Project, scenarios: list[str] | None = None, *,
                  pictures: bool = True, fresh: bool = True,
                  workers: int | None = None) -> dict[str, dict]:
    """Write the build folders of the selected scenarios; return per-scenario build facts.

    With ``fresh=False`` a folder that is current (:func:`build_staleness`, and its picture
    there when ``pictures``) is kept and its facts read from its manifest. The folders are
    built by this process and ``workers − 1`` spawned ones (default: the usable cores, when
    there are at least :data:`PARALLEL_MIN` folders to build), heaviest first; each folder is
    the same whichever process wrote it."""
    engine = folder_engine()
    chosen = selected(project, scenarios)
    facts: dict[str, dict] = {}
    build_root = project.build_dir
    build_root.mkdir(parents=True, exist_ok=True)
    drawn = {sc.name for sc in chosen if pictures and project.district is None
             and not is_later_realisation(sc.name)}   # the report shows F@1's picture
    todo = []
    for sc in chosen:
        kept = None if fresh else _current_facts(project, sc, sc.name in drawn)
        if kept is None:
            todo.append(sc)
        else:
            facts[sc.name] = kept
            log.info("  %s: current, kept (--fresh rebuilds it) → %s", sc.name,
                     build_root / sc.name)
    weight = {sc.name: _weight(project, sc) for sc in todo}
    n = min(len(todo), usable_cores() if workers is None else max(1, int(workers)))
    if workers is None and sum(w > 0 for w in weight.values()) < PARALLEL_MIN:
        n = 1     # crowns from the cache (or none): a folder takes ~0.1 s, a worker ~1 s
    bar = progress(None, desc="build", total=len(todo), unit="scenario")
    with _Pictures(len(drawn & {sc.name for sc in todo})) as painter:
        def done(name: str, built_facts: dict) -> None:
            facts[name] = built_facts
            if name in drawn:
                painter.draw(build_root / name)
            log.info("%s", _built_line(built_facts, build_root / name))
            log_notes(name, built_facts["notes"])
            bar.update(1)

        try:
            _build_all(project, sorted(todo, key=lambda sc: weight[sc.name], reverse=True),
                       engine, build_root, n, done)
        finally:
            bar.close()
    _remove_stale_builds(project, chosen)
    engine.write_index(build_root, [s.name for s in selected(project, None)
                                    if (build_root / s.name).exists()])
    return {sc.name: facts[sc.name] for sc in chosen}


#: at least this many crowns to build (not in the build cache) before workers are spawned
#: (a spawned interpreter takes ~1 s to import radtree; a crown 0.1–3 s to build)
PARALLEL_MIN = 4


def _weight(project: Project, sc: Scenario) -> int:
    """A rough build cost, for the order of the queue (heaviest first): crowns made from a
    photo (its analysis; a dome's cut along its sky outlines) 3, free crowns 2, other crowns
    1; 0 without a crown or with the crown in the build cache (:mod:`radtree.cache`)."""
    from radtree.config.photo import photo_of
    from radtree.trees.build import crown_in_cache, scenario_tree

    if sc.model == "none":
        return 0
    try:
        eff = effective_project(project, sc) if project.district is None else project
        tree, _, form = scenario_tree(eff, sc)
        if project.district is None and crown_in_cache(eff, sc, facade_frame(eff), (tree, form)):
            return 0
    except RadtreeError:
        return 0   # the build itself reports the error
    return 3 if photo_of(tree)[0] is not None else 1 + int(form == "free")


def _build_all(project: Project, queue: list[Scenario], engine: Any, build_root: Path,
               n: int, done: Callable[[str, dict], None]) -> None:
    """Build ``queue`` (heaviest first) here and in ``n − 1`` spawned workers: this process
    takes scenarios from the front — it starts at once, and the photo crowns that share a
    photo's analysis stay in one process — the workers from the back, each given up to two
    ahead so it never waits for this process. ``done(name, facts)`` is called here for each
    folder once it is written. A worker's error is raised here, the scenarios not started
    yet are cancelled."""
    pending = deque(queue)
    if n <= 1:
        while pending:
            sc = pending.popleft()
            done(sc.name, _build_one(project, sc, engine, build_root))
        return
    pool = ProcessPoolExecutor(n - 1, mp_context=multiprocessing.get_context("spawn"))
    outstanding: dict[Future[dict], str] = {}

    def top_up() -> None:
        while pending and len(outstanding) < 2 * (n - 1):
            sc = pending.pop()
            outstanding[pool.submit(_build_in_worker, project, sc, build_root)] = sc.name

    def collect(block: bool) -> None:
        if outstanding:
            ready, _ = wait(outstanding, timeout=None if block else 0,
                            return_when=FIRST_COMPLETED)
            for f in ready:
                name = outstanding.pop(f)
                try:
                    built = f.result()
                except BrokenProcessPool:   # every worker's folders: their atomic_dirs
                    for gone in [name, *outstanding.values()]:
                        for tmp in build_root.glob(f".{gone}.*"):
                            shutil.rmtree(tmp, ignore_errors=True)
                    raise RadtreeError(
                        f"the worker process building {name} ended abruptly (killed, or out of "
                        "memory?); `radtree build --workers 1` builds in one process") from None
                done(name, built)

    try:
        mine = pending.popleft()
        top_up()
        while True:
            done(mine.name, _build_one(project, mine, engine, build_root))
            collect(block=False)
            top_up()
            if not pending:
                break
            mine = pending.popleft()
        while outstanding:
            collect(block=True)
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _build_in_worker(project: Project, sc: Scenario, build_root: Path) -> dict:
    """:func:`_build_one` in a spawned worker (its own folder engine)."""
    return _build_one(project, sc, folder_engine(), build_root)


def _built_line(f: dict, folder: Path) -> str:
    return (f"  {f['scenario']}: {f['model']} ({f['form']}), {f['triangles']} triangles, "
            f"-ab {f['ab']}, geometry {f['seconds']['geometry']:.2f} s"
            f"{' (crown from the cache)' if f.get('crown_from_cache') else ''} → {folder}")


def _current_facts(project: Project, sc: Scenario, picture: bool) -> dict | None:
    """The build facts of ``build/<sc>/`` when that folder is current (and holds its
    picture when ``picture``), else None."""
    folder = project.build_dir / sc.name
    if build_staleness(project, sc) or (picture and not (folder / "model.png").is_file()):
        return None
    try:
        return dict(json.loads((folder / "manifest.json").read_text())["build"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


class _Pictures:
    """Draws ``model.png`` of the build folders from their ``scene.pickle``: in one spawned
    worker process while the next folders are built (two usable cores or more and several
    pictures), else here. Every picture is written (atomically) before the context ends; a
    drawing error is raised then."""

    def __init__(self, count: int):
        self._pool = (ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
                      if count > 1 and usable_cores() > 1 else None)
        self._futures: list[Future[None]] = []

    def __enter__(self) -> _Pictures:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._pool is None:
            return
        try:
            if exc[0] is None:
                for f in self._futures:
                    f.result()
        finally:
            self._pool.shutdown(wait=True, cancel_futures=True)

    def draw(self, folder: Path) -> None:
        if self._pool is None:
            draw_model_png(folder)
        else:
            self._futures.append(self._pool.submit(draw_model_png, folder))


def draw_model_png(folder: Path) -> None:
    """``folder/model.png``: the crown model of the folder's ``scene.pickle`` (none without
    a crown); copied from the build cache when the same crown and scene were drawn before
    (0.6–0.8 s a picture otherwise)."""
    import hashlib

    from radtree.cache import cached_file, content_key
    from radtree.trees.picture import render_model_png

    with (folder / SCENE_FILE).open("rb") as f:
        built = pickle.load(f)
    if built.tree is None:
        return
    tree, scene = built.tree, built.scene
    key = content_key(*(a for m in scene.meshes for a in (m.vertices, m.faces)),
                      what="model.png", meshes=[(m.name, m.material) for m in scene.meshes],
                      crown=[m.name for m in tree.meshes], model=tree.model, form=tree.form,
                      triangles=tree.triangles, seconds=tree.build_seconds, info=tree.info,
                      frame=tree.frame, grids=hashlib.sha256(pickle.dumps(scene.grids)).hexdigest())
    cached_file(key, ".png", lambda p: render_model_png(tree, scene, p), folder / "model.png")


def _build_one(project: Project, sc: Scenario, engine: Any, build_root: Path) -> dict:
    """Write ``build/<sc>/``; return its build facts."""
    from radtree.trees.points_crown import points_record

    t0 = time.perf_counter()
    states = hour_states(project, sc)
    prep = time.perf_counter() - t0
    built = make_scene(project, sc)
    t1 = time.perf_counter()
    with atomic_dir(build_root / sc.name) as tmp:
        names = list(built.scene.grids)
        at = {st.label: hour_grids(project, st.time, names, None, sc) for st in states}
        engine.write_folder(built.scene, states, effective_project(project, sc).engine,
                            built.ab, tmp, sc.name, at)
        facts = {
            "scenario": sc.name, "model": sc.model, "reflection": sc.reflection,
            "form": sc.form or project.tree.form, "ab": built.ab,
            "triangles": built.triangles, "notes": built.notes, "info": built.info,
            "params_hash": project.params_hash(sc),
            "photo": getattr(built.tree, "photo", None),
            "crown_from_cache": bool(getattr(built.tree, "from_cache", False)),
            "points_crown": points_record(effective_project(project, sc).tree.points,
                                          built.info),
            "seconds": {"preparation": prep, "geometry": built.geometry_seconds,
                        "writing": time.perf_counter() - t1},
        }
        with (tmp / SCENE_FILE).open("wb") as f:   # inside the atomic folder
            pickle.dump(built, f, protocol=5)
        write_text(tmp / "manifest.json", json.dumps(
            manifest(project, extra={"build": facts, "files": folder_files(tmp)},
                     engines=[engine]),   # the folder's engine: it wrote the folder
            indent=2, default=str))
    return facts


def built_scene(project: Project, sc: Scenario) -> BuiltScene:
    """``make_scene(project, sc)``: loaded from ``build/<sc>/scene.pickle`` when that folder is
    current (:func:`build_staleness`: same radtree version, parameters and files — the
    pickle's checksum included), else built anew. The photo crowns take 1–2 s to build, the
    pickle milliseconds to load."""
    path = project.build_dir / sc.name / SCENE_FILE
    if path.is_file() and build_is_current(project, sc):
        try:
            with path.open("rb") as f:
                built = pickle.load(f)
            if isinstance(built, BuiltScene):
                return built
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError):
            pass   # unreadable: built anew below
    return make_scene(project, sc)


#: radtree's in-memory scene of a build folder (:func:`built_scene`)
SCENE_FILE = "scene.pickle"
#: written by the engine while tracing (not part of the built scene)
_OUTPUTS = ("manifest.json", "model.png", "octrees", "results")


def folder_files(folder: Path) -> dict[str, list]:
    """``relative path → [bytes, sha256]`` of every scene file of a build folder."""
    return {str(f.relative_to(folder)): [f.stat().st_size, file_sha256(f)]
            for f in sorted(folder.rglob("*"))
            if f.is_file() and f.relative_to(folder).parts[0] not in _OUTPUTS}


def build_staleness(project: Project, sc: Scenario) -> str:
    """Why ``build/<scenario>/`` cannot be used ("" when it can): missing, written by another
    radtree version or for other parameters, or a scene file missing or changed since."""
    folder = project.build_dir / sc.name
    try:
        mf = json.loads((folder / "manifest.json").read_text())
        version, phash, files = mf["radtree_version"], mf["build"]["params_hash"], mf["files"]
    except FileNotFoundError:
        return "is missing"
    except (OSError, ValueError, KeyError, TypeError):
        return "has no valid manifest.json (written by an older radtree?)"
    if version != radtree.__version__:
        return f"was written by radtree {version} (this is {radtree.__version__})"
    if phash != project.params_hash(sc):
        return "was written for other parameters"
    now = folder_files(folder)
    gone = sorted(set(files) - set(now))
    if gone:
        return f"lacks {', '.join(gone)}"
    changed = sorted(k for k in files if list(now[k]) != list(files[k]))
    if changed:
        return f"has {', '.join(changed)} changed since it was built"
    return ""


def build_is_current(project: Project, sc: Scenario) -> bool:
    """True when ``build/<scenario>/`` is as this radtree built it for the scenario's
    parameters (see :func:`build_staleness`)."""
    return not build_staleness(project, sc)


def ensure_built(project: Project, sc: Scenario) -> Path:
    """The scenario's build folder, (re)built first when missing or stale (logged why)."""
    why = build_staleness(project, sc)
    if why:
        log.info("  build/%s %s: building it", sc.name, why)
        build_project(project, [sc.name])
    return project.build_dir / sc.name


def _remove_stale_builds(project: Project, built: list[Scenario]) -> None:
    """A scenario is built either as one folder or as realisation folders (``F@k``): remove
    the other kind, and realisations beyond the current count, so no stale crown is reported."""
    for parent in dict.fromkeys(parent_name(sc.name) for sc in built):
        current = {sc.name for sc in realisations_of(project, project.scenario(parent))}
        for folder in [project.build_dir / parent,
                       *project.build_dir.glob(f"{parent}{REALISATION_MARK}*")]:
            if folder.is_dir() and folder.name not in current:
                shutil.rmtree(folder)
