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
import multiprocessing
import pickle
import shutil
import time
from collections.abc import Callable, Iterable
from concurrent.futures import Future, ProcessPoolExecutor
from pathlib import Path
from typing import Any

import radtree
from radtree.config import Project, Scenario, effective_project
from radtree.engines.registry import folder_engine
from radtree.fileio import atomic_dir, write_text
from radtree.light.hours import hour_states
from radtree.pipeline.assemble import BuiltScene, make_scene
from radtree.pipeline.manifest import file_sha256, manifest
from radtree.pipeline.processes import usable_cores
from radtree.pipeline.realisations import (
    REALISATION_MARK,
    is_later_realisation,
    parent_name,
    realisations_of,
    selected,
)


def hour_grids(project: Project, time_: str, available: list[str],
               wanted: list[str] | None, sc: Scenario | None = None) -> list[str]:
    """Grids to trace at an hour: the dense façade map only at ``sensors.dense_hours``, and
    only in the first crown realisation (``F@1``) of a scenario with several."""
    use = [g for g in available if wanted is None or g in wanted]
    dense = project.sensors.dense_hours
    if (dense and time_ not in dense) or (sc is not None and is_later_realisation(sc.name)):
        use = [g for g in use if g != "facade_map"]
    return use


def build_project(project: Project, scenarios: list[str] | None = None,
                  echo: Callable[[str], None] = print, progress: bool = True,
                  pictures: bool = True) -> dict[str, dict]:
    """Write the build folders of the selected scenarios; return per-scenario build facts."""
    engine = folder_engine()
    chosen = selected(project, scenarios)
    facts: dict[str, dict] = {}
    build_root = project.build_dir
    build_root.mkdir(parents=True, exist_ok=True)
    drawn = [sc for sc in chosen if pictures and project.district is None
             and not is_later_realisation(sc.name)]   # the report shows F@1's picture
    with _Pictures(len(drawn)) as painter:
        for sc in progress_bar(chosen, "build", progress, unit="scenario"):
            _build_one(project, sc, engine, build_root, facts, painter if sc in drawn else None,
                       echo)
    _remove_stale_builds(project, chosen)
    engine.write_index(build_root, [s.name for s in selected(project, None)
                                    if (build_root / s.name).exists()])
    return facts


class _Pictures:
    """Draws ``model.png`` of the build folders: in one spawned worker process while the next
    folders are built (two usable cores or more and several pictures), else here. Every
    picture is written (atomically) before the context ends; a drawing error is raised then."""

    def __init__(self, count: int):
        self._pool = (ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
                      if count > 1 and usable_cores() > 1 else None)
        self._futures: list[Future[Path]] = []

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

    def draw(self, tree: Any, scene: Any, path: Path) -> None:
        from radtree.trees.picture import render_model_png

        if self._pool is None:
            render_model_png(tree, scene, path)
        else:
            self._futures.append(self._pool.submit(render_model_png, tree, scene, path))


def _build_one(project: Project, sc: Scenario, engine: Any, build_root: Path,
               facts: dict[str, dict], painter: _Pictures | None,
               echo: Callable[[str], None]) -> None:
    """Write ``build/<sc>/`` (its picture drawn by ``painter`` when given) into ``facts``."""
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
        facts[sc.name] = {
            "scenario": sc.name, "model": sc.model, "reflection": sc.reflection,
            "form": sc.form or project.tree.form, "ab": built.ab,
            "triangles": built.triangles, "notes": built.notes, "info": built.info,
            "params_hash": project.params_hash(sc),
            "photo": getattr(built.tree, "photo", None),
            "seconds": {"preparation": prep, "geometry": built.geometry_seconds,
                        "writing": time.perf_counter() - t1},
        }
        with (tmp / SCENE_FILE).open("wb") as f:   # inside the atomic folder
            pickle.dump(built, f, protocol=5)
        write_text(tmp / "manifest.json", json.dumps(
            manifest(project, extra={"build": facts[sc.name], "files": folder_files(tmp)}),
            indent=2, default=str))
    if painter is not None and built.tree is not None:   # model.png: not a scene file
        painter.draw(built.tree, built.scene, build_root / sc.name / "model.png")
    echo(f"  {sc.name}: {sc.model} ({facts[sc.name]['form']}), {built.triangles} triangles, "
         f"-ab {built.ab}, geometry {built.geometry_seconds:.2f} s → {build_root / sc.name}")


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


def ensure_built(project: Project, sc: Scenario, echo: Callable[[str], None]) -> Path:
    """The scenario's build folder, (re)built first when missing or stale (said why)."""
    why = build_staleness(project, sc)
    if why:
        echo(f"  build/{sc.name} {why}: building it")
        build_project(project, [sc.name], echo=echo, progress=False)
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


def progress_bar(items: Iterable | None, desc: str, enabled: bool, total: int | None = None,
                 unit: str = "hour") -> Any:
    """A tqdm progress bar on stderr over ``items`` (or of ``total`` steps), or the plain
    iterable / None when disabled."""
    if not enabled:
        return items
    from tqdm import tqdm

    if items is None:
        return tqdm(total=total, desc=desc, unit=unit, leave=False)
    return tqdm(items, desc=desc, unit=unit, leave=False)
