"""From a project to scenes, build folders and the tidy results table.

``build_project`` writes ``PROJECT/build/<scenario>/`` (Radiance files, Makefile, model
picture, manifest) and a top-level ``PROJECT/build/Makefile``; ``simulate_project`` traces every
scenario × hour with the chosen engine and writes ``PROJECT/results/illuminance.csv``. Finished
(scenario, hour) parts are kept in ``results/parts/`` keyed by the scenario's parameter hash, so
an interrupted run resumes where it stopped.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.engines.base import RESULT_COLUMNS, GridResult
from radtree.errors import ConfigError, RadtreeError
from radtree.fileio import atomic_path, write_text
from radtree.light.ground import calculated_reflection, reflection_choice, unfiltered_ground_light
from radtree.light.hours import hour_states
from radtree.light.sky import SkyState
from radtree.manifest import manifest
from radtree.scene import Scene
from radtree.sensor_grid import facade_circle, facade_dense_grid
from radtree.site.frame import FacadeFrame
from radtree.site.street import street_materials, street_meshes


@dataclass
class BuiltScene:
    """A scenario's scene plus what the build learnt about it."""

    scenario: Scenario
    scene: Scene
    ab: int
    notes: list[str]
    triangles: int
    geometry_seconds: float
    info: dict[str, float] = field(default_factory=dict)
    tree: Any = None


def facade_frame(project: Project) -> FacadeFrame:
    return FacadeFrame(azimuth_deg=project.street.facade_azimuth_deg)


def make_scene(project: Project, scenario: Scenario, dense_grid: bool | None = None) -> BuiltScene:
    """The in-memory scene of one scenario: street canyon, crown model, sensor grids."""
    project = effective_project(project, scenario)
    frame = facade_frame(project)
    materials: dict = dict(street_materials(project.street))
    meshes = street_meshes(project.street, frame)
    grids = {"facade": facade_circle(project.sensors, frame)}
    use_dense = project.sensors.dense_grid if dense_grid is None else dense_grid
    if use_dense:
        grids["facade_map"] = facade_dense_grid(project.sensors, frame)
    notes = [f"street canyon {project.street.width_m:g} m wide, façade looks "
             f"{project.street.facade_azimuth_deg:g}° (compass), façade ρ "
             f"{project.street.facade_reflectance:g}"]
    if project.office is not None:
        from radtree.site.office import office_parts

        o_meshes, o_materials, o_grids, o_notes = office_parts(project, frame)
        meshes = [m for m in meshes if m.name != "facade"] + o_meshes
        materials.update(o_materials)
        grids = o_grids
        notes += o_notes
    t0 = time.perf_counter()
    ab = 2
    info: dict[str, float] = {}
    tree = None
    if scenario.model != "none":
        from radtree.trees.build import build_tree

        tree = build_tree(project, scenario, frame)
        clash = set(tree.materials) & set(materials)
        if clash:
            raise RadtreeError(f"crown model materials clash with the street's: {clash}")
        materials.update(tree.materials)
        meshes = meshes + list(tree.meshes)
        notes += list(tree.notes)
        ab = int(tree.recommended_ab)
        info = dict(tree.info)
    geometry_seconds = time.perf_counter() - t0
    if project.extra_geometry:
        from radtree.site.user_geometry import load_user_meshes

        meshes = meshes + load_user_meshes(project.extra_geometry, materials)
    if project.office is not None:
        from radtree.site.office import RECOMMENDED_AB

        ab = max(ab, RECOMMENDED_AB)   # rooms need ~6 bounces (see the office notes)
    if project.engine.ab is not None:
        ab = project.engine.ab
    scene = Scene(meshes, materials, grids, notes)
    return BuiltScene(scenario, scene, ab, notes, scene.n_triangles, geometry_seconds, info, tree)


REALISATION_MARK = "@"   # "F@3": the third random crown of scenario F


def realisations_of(project: Project, sc: Scenario) -> list[Scenario]:
    """The scenario as traced: itself or, for a louvers crown with ``louvers.realisations``
    N > 1, N copies named ``<name>@k`` whose ``louvers.seed`` is seed + k − 1 (k = 1…N);
    ``simulate`` averages them back into ``<name>``."""
    if sc.model != "louvers":
        return [sc]
    from radtree.trees.build import apply_switches

    tree, _ = apply_switches(project.tree, dict(sc.switches), source=str(project.source))
    n = tree.louvers.realisations
    if n <= 1:
        return [sc]
    return [replace(sc, name=f"{sc.name}{REALISATION_MARK}{k}",
                    switches={**sc.switches, "louvers.seed": tree.louvers.seed + k - 1,
                              "louvers.realisations": 1})
            for k in range(1, n + 1)]


def parent_name(name: str) -> str:
    """``F@3`` → ``F``; other names unchanged."""
    return str(name).partition(REALISATION_MARK)[0]


def is_later_realisation(name: str) -> bool:
    """True for ``F@2``, ``F@3``, …: crowns after the first (maps and checks use the first)."""
    return str(name).partition(REALISATION_MARK)[2] not in ("", "1")


def selected(project: Project, names: list[str] | None) -> list[Scenario]:
    """The scenarios to build or trace, each expanded into its crown realisations; a name may
    also pick one realisation (``F@2``)."""
    out: list[Scenario] = []
    for name in names or [sc.name for sc in project.scenarios]:
        parent, mark, k = name.partition(REALISATION_MARK)
        subs = realisations_of(project, project.scenario(parent))
        if not mark:
            out.extend(subs)
        elif k.isdigit() and len(subs) > 1 and 1 <= int(k) <= len(subs):
            out.append(subs[int(k) - 1])
        else:
            raise ConfigError(f"scenario {parent!r} has no realisation {name!r} "
                              f"(it has {len(subs) if len(subs) > 1 else 'no'} realisations)",
                              source=str(project.source), field="scenario")
    return out


def merge_realisations(table: pd.DataFrame, hashes: dict[str, str]
                       ) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """Average the rows of ``<name>@k`` realisations into ``<name>``: ``lux``/``lux_traced`` are
    the means over realisations, ``lux_stderr`` the standard error over them (s.d./√n, which
    includes the tracing noise), ``lux_realisation_sd`` and ``realisations`` are added; a grid
    traced in one realisation only (the dense map) keeps its values. ``hashes`` maps a parent
    name to its parameter hash. Returns (merged table, the per-realisation rows or None)."""
    names = table["scenario"].astype(str)
    is_sub = names.str.contains(REALISATION_MARK, regex=False)
    if not is_sub.any():
        return table, None
    sub = table[is_sub].copy()
    parts = names[is_sub].str.partition(REALISATION_MARK)
    sub["scenario"] = parts[0]
    sub["realisation"] = parts[2].astype(int)
    keys = ["scenario", "time", "grid", "sensor"]
    g = sub.groupby(keys, sort=False)
    stats = pd.DataFrame({"lux": g["lux"].mean(), "lux_traced": g["lux_traced"].mean(),
                          "sd": g["lux"].std(ddof=1), "n": g["lux"].size()})
    merged = (sub.sort_values("realisation").drop_duplicates(keys).drop(columns="realisation")
              .set_index(keys))
    stats = stats.reindex(merged.index)
    merged["lux"] = stats["lux"]
    merged["lux_traced"] = stats["lux_traced"]
    several = stats["n"] > 1
    merged["lux_stderr"] = np.where(several, stats["sd"] / np.sqrt(stats["n"]),
                                    merged["lux_stderr"])
    merged["lux_realisation_sd"] = np.where(several, stats["sd"], np.nan)
    merged["realisations"] = stats["n"]
    merged = merged.reset_index()
    merged["params_hash"] = merged["scenario"].map(hashes).fillna(merged["params_hash"])
    return pd.concat([table[~is_sub], merged], ignore_index=True), sub


# ---------------------------------------------------------------- build
def build_project(project: Project, scenarios: list[str] | None = None,
                  echo: Callable[[str], None] = print, progress: bool = True,
                  pictures: bool = True) -> dict[str, dict]:
    """Write the Radiance build folders; return per-scenario build facts."""
    from radtree.engines.radiance.binaries import find_radiance
    from radtree.engines.radiance.writer import write_build
    from radtree.fileio import atomic_dir

    install = find_radiance()
    chosen = selected(project, scenarios)
    facts: dict[str, dict] = {}
    build_root = project.build_dir
    build_root.mkdir(parents=True, exist_ok=True)
    for sc in _bar(chosen, "build", progress):
        t0 = time.perf_counter()
        states = hour_states(project, sc)
        prep = time.perf_counter() - t0
        built = make_scene(project, sc)
        t1 = time.perf_counter()
        with atomic_dir(build_root / sc.name) as tmp:
            names = list(built.scene.grids)
            at = {st.label: hour_grids(project, st.time, names, None, sc) for st in states}
            write_build(built.scene, states, effective_project(project, sc).engine, built.ab,
                        tmp, install, sc.name, hour_grids=at)
            if pictures and built.tree is not None:
                from radtree.trees.picture import render_model_png

                render_model_png(built.tree, built.scene, tmp / "model.png")
            facts[sc.name] = {
                "scenario": sc.name, "model": sc.model, "reflection": sc.reflection,
                "form": sc.form or project.tree.form, "ab": built.ab,
                "triangles": built.triangles, "notes": built.notes, "info": built.info,
                "params_hash": project.params_hash(sc),
                "seconds": {"preparation": prep, "geometry": built.geometry_seconds,
                            "writing": time.perf_counter() - t1},
            }
            write_text(tmp / "manifest.json", json.dumps(
                manifest(project, extra={"build": facts[sc.name]}), indent=2, default=str))
        echo(f"  {sc.name}: {sc.model} ({facts[sc.name]['form']}), {built.triangles} triangles, "
             f"-ab {built.ab}, geometry {built.geometry_seconds:.2f} s → {build_root / sc.name}")
    _remove_stale_builds(project, chosen)
    _write_top_makefile(project, [s.name for s in selected(project, None)
                                  if (build_root / s.name).exists()])
    return facts


def _remove_stale_builds(project: Project, built: list[Scenario]) -> None:
    """A scenario is built either as one folder or as realisation folders (``F@k``): remove
    the other kind, and realisations beyond the current count, so no stale crown is reported."""
    import shutil

    for parent in dict.fromkeys(parent_name(sc.name) for sc in built):
        current = {sc.name for sc in realisations_of(project, project.scenario(parent))}
        for folder in [project.build_dir / parent,
                       *project.build_dir.glob(f"{parent}{REALISATION_MARK}*")]:
            if folder.is_dir() and folder.name not in current:
                shutil.rmtree(folder)


def _write_top_makefile(project: Project, names: list[str]) -> None:
    lines = ["# Generated by radtree: runs every scenario's Makefile (make -j2 -C build).", "",
             f"SCENARIOS := {' '.join(names)}", "", ".PHONY: all clean $(SCENARIOS)",
             "all: $(SCENARIOS)", "", "$(SCENARIOS):", "\t$(MAKE) -C $@", "",
             "clean:", "\tfor s in $(SCENARIOS); do $(MAKE) -C $$s clean; done", ""]
    write_text(project.build_dir / "Makefile", "\n".join(lines))


# ---------------------------------------------------------------- simulate
def choose_engine(name: str) -> str:
    """``auto`` → radiance when found, else numpy."""
    from radtree.engines.radiance.binaries import find_radiance

    if name == "auto":
        return "radiance" if find_radiance() is not None else "numpy"
    if name == "radiance" and find_radiance() is None:
        raise RadtreeError("engine 'radiance' asked for, but Radiance was not found "
                           "(install pyradiance, or use --engine numpy)")
    if name not in ("radiance", "numpy"):
        raise ConfigError(f"unknown engine {name!r} (radiance, numpy or auto)")
    return name


def _rows(project: Project, sc: Scenario, st: SkyState, scene: Scene,
          res: dict[str, GridResult], engine: str, phash: str) -> pd.DataFrame:
    frames = []
    for gname, gr in res.items():
        grid = scene.grids[gname]
        extra = np.zeros(len(grid))
        if sc.reflection == "calculated":
            extra = calculated_reflection(project, sc, st, grid)
        extra = extra + unfiltered_ground_light(project, sc, st, grid)
        frames.append(pd.DataFrame({
            "scenario": sc.name, "model": sc.model, "datetime": st.datetime.isoformat(),
            "time": st.time, "grid": gname, "sensor": np.arange(len(grid)), "row": grid.rows,
            "x": grid.points[:, 0], "y": grid.points[:, 1], "z": grid.points[:, 2],
            "lux": gr.lux + extra,
            "lux_stderr": gr.stderr if gr.stderr is not None else np.nan,
            "engine": engine, "params_hash": phash,
            "lux_traced": gr.lux, "lux_reflected_calc": extra,
            "reflection": sc.reflection,
        }))
    return pd.concat(frames, ignore_index=True)


def trace_numpy(project: Project, sc: Scenario, rays: int | None = None, seed: int | None = None,
                grids: list[str] | None = None) -> pd.DataFrame:
    """Every hour of one scenario with the NumPy engine, in memory: the rows ``simulate``
    would write (calculated reflection included), nothing written to disk."""
    from radtree.engines.numpy.engine import trace_hour

    built = make_scene(project, sc, dense_grid=False)
    eng = effective_project(project, sc).engine
    params = replace(eng, ab=built.ab, max_bounces=built.ab, rays=rays or eng.rays,
                     seed=eng.seed if seed is None else seed)
    phash = project.params_hash(sc)
    frames = []
    for st in hour_states(project, sc):
        use = [g for g in built.scene.grids if grids is None or g in grids]
        res = trace_hour(built.scene, st, params, grids=use)
        frames.append(_rows(project, sc, st, built.scene, res, "numpy", phash))
    return pd.concat(frames, ignore_index=True)


@dataclass
class SimulationOutcome:
    table: pd.DataFrame
    path: Path
    timing: pd.DataFrame
    computed: int
    reused: int
    engine: str


def simulate_project(project: Project, engine: str = "auto", scenarios: list[str] | None = None,
                     hours: list[str] | None = None, workers: int | None = None,
                     dry_run: bool = False, echo: Callable[[str], None] = print,
                     progress: bool = True, resume: bool = True,
                     grids: list[str] | None = None) -> SimulationOutcome | None:
    """Trace every selected scenario × hour and write ``results/illuminance.csv``."""
    eng = choose_engine(engine if engine != "auto" else project.engine.name)
    chosen = selected(project, scenarios)
    workers = workers or project.engine.workers
    parts_dir = project.results_dir / "parts"
    tasks = []
    timing: dict[str, dict[str, float]] = {}
    prepared: dict[str, tuple[BuiltScene, list[SkyState], str, object]] = {}
    for sc in chosen:
        t0 = time.perf_counter()
        states = hour_states(project, sc, hours)
        phash = project.params_hash(sc)
        prep = time.perf_counter() - t0
        built = make_scene(project, sc)
        plan = None
        if eng == "radiance":
            plan = _radiance_plan(project, sc, built, states, echo)
        prepared[sc.name] = (built, states, phash, plan)
        timing[sc.name] = {"preparation_s": prep, "geometry_s": built.geometry_seconds,
                           "tracing_s": 0.0}
        for st in states:
            tasks.append((sc, st))
    if dry_run:
        from radtree.engines.radiance.engine import run_hour

        for sc, st in tasks:
            built, _, _, plan = prepared[sc.name]
            if eng == "radiance":
                run_hour(plan, st.label, dry_run=True, echo=echo)  # type: ignore[arg-type]
            else:
                echo(f"numpy engine: {sc.name} {st.time}, {built.triangles} triangles, "
                     f"{project.engine.rays} rays/sensor")
        return None

    parts_dir.mkdir(parents=True, exist_ok=True)
    lock = threading.Lock()
    frames: list[pd.DataFrame] = []
    todo = []
    reused = 0
    for sc, st in tasks:
        part = parts_dir / f"{sc.name}_{st.label}_{eng}_{prepared[sc.name][2]}.csv"
        if resume and part.exists():
            frames.append(pd.read_csv(part))
            reused += 1
        else:
            todo.append((sc, st, part))

    def work(item):
        sc, st, part = item
        built, _, phash, plan = prepared[sc.name]
        t = time.perf_counter()
        use = hour_grids(project, st.time, list(built.scene.grids), grids, sc)
        if eng == "radiance":
            from radtree.engines.radiance.engine import run_hour

            res = run_hour(plan, st.label, grids=use)  # type: ignore[arg-type]
        else:
            from radtree.engines.numpy.engine import trace_hour

            # like-for-like with Radiance: as many diffuse bounces as -ab
            params = replace(effective_project(project, sc).engine, ab=built.ab,
                             max_bounces=built.ab)
            res = trace_hour(built.scene, st, params, grids=use)
        df = _rows(project, sc, st, built.scene, res, eng, phash)
        with atomic_path(part) as tmp:
            df.to_csv(tmp, index=False)
        with lock:
            timing[sc.name]["tracing_s"] += time.perf_counter() - t
        return df

    if todo:
        bar = _bar(None, f"simulate ({eng})", progress, total=len(todo))
        with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
            futures = {pool.submit(work, item): item for item in todo}
            try:
                for fut in as_completed(futures):
                    frames.append(fut.result())
                    if bar is not None:
                        bar.update(1)
            except BaseException:
                for f in futures:
                    f.cancel()
                raise
            finally:
                if bar is not None:
                    bar.close()
    table = pd.concat(frames, ignore_index=True)
    parents = list(dict.fromkeys(parent_name(sc.name) for sc in chosen))
    table, per_realisation = merge_realisations(
        table, {p: project.params_hash(project.scenario(p)) for p in parents})
    if per_realisation is not None:
        _merge_write(project.results_dir / "realisations.csv", per_realisation, parents)
    order = {s.name: i for i, s in enumerate(project.scenarios)}
    table = table.sort_values(["scenario", "time", "grid", "sensor"],
                              key=lambda c: c.map(order) if c.name == "scenario" else c)
    cols = RESULT_COLUMNS + [c for c in table.columns if c not in RESULT_COLUMNS]
    table = table[cols].reset_index(drop=True)
    out = project.results_dir / "illuminance.csv"
    _merge_write(out, table, parents)
    summed: dict[str, dict[str, float]] = {}
    for name, v in timing.items():
        acc = summed.setdefault(parent_name(name), dict.fromkeys(v, 0.0))
        for k, x in v.items():
            acc[k] += x
    tdf = pd.DataFrame([{"scenario": k, "engine": eng, **v} for k, v in summed.items()])
    _merge_timing(project.results_dir / "timing.csv", tdf)
    if project.office is not None:
        from radtree.office_summary import write_summary

        write_summary(project, maps=False)
    write_text(project.results_dir / "manifest.json", json.dumps(
        manifest(project, extra={"engine": eng, "scenarios": [s.name for s in chosen]}),
        indent=2, default=str))
    return SimulationOutcome(pd.read_csv(out), out, tdf, len(todo), reused, eng)


def hour_grids(project: Project, time_: str, available: list[str],
               wanted: list[str] | None, sc: Scenario | None = None) -> list[str]:
    """Grids to trace at an hour: the dense façade map only at ``sensors.dense_hours``, and
    only in the first crown realisation (``F@1``) of a scenario with several."""
    use = [g for g in available if wanted is None or g in wanted]
    dense = project.sensors.dense_hours
    if (dense and time_ not in dense) or (sc is not None and is_later_realisation(sc.name)):
        use = [g for g in use if g != "facade_map"]
    return use


def _merge_write(out: Path, table: pd.DataFrame, names: list[str]) -> None:
    """Replace the named scenarios' rows in an existing table, keep the others."""
    if out.exists():
        old = pd.read_csv(out)
        old = old[~old["scenario"].astype(str).isin(names)]
        table = pd.concat([old, table], ignore_index=True) if len(old) else table
    with atomic_path(out) as tmp:
        table.to_csv(tmp, index=False)


def _merge_timing(out: Path, tdf: pd.DataFrame) -> None:
    if out.exists():
        old = pd.read_csv(out)
        old = old[~old["scenario"].astype(str).isin(tdf["scenario"].astype(str))]
        tdf = pd.concat([old, tdf], ignore_index=True)
    with atomic_path(out) as tmp:
        tdf.to_csv(tmp, index=False)


def _radiance_plan(project: Project, sc: Scenario, built: BuiltScene, states: list[SkyState],
                   echo: Callable[[str], None]):
    """The scenario's build plan; (re)builds the folder when missing or stale."""
    from radtree.engines.radiance.binaries import find_radiance
    from radtree.engines.radiance.writer import BuildPlan, rtrace_options

    folder = project.build_dir / sc.name
    mf = folder / "manifest.json"
    phash = project.params_hash(sc)
    stale = True
    if mf.exists():
        try:
            stale = json.loads(mf.read_text())["build"]["params_hash"] != phash
        except (ValueError, KeyError):
            stale = True
    if stale:
        echo(f"  build/{sc.name} is missing or out of date: building it")
        build_project(project, [sc.name], echo=echo, progress=False)
    install = find_radiance()
    del install
    wanted = {s.label for s in states}
    plan = BuildPlan(folder=folder, hours=[s.label for s in states],
                     grids=list(built.scene.grids), scene_files=["materials.rad"],
                     hour_files={}, rtrace_opts=rtrace_options(effective_project(project, sc).engine,
                                                           built.ab),
                     states={s.label: s for s in states})
    geometry = sorted(str(p.relative_to(folder)) for p in (folder / "geometry").glob("*.rad"))
    for label in wanted:
        files = []
        ground = folder / "skies" / f"{label}_ground.rad"
        if ground.exists():
            files.append(str(ground.relative_to(folder)))
        plan.hour_files[label] = files + geometry + [f"skies/{label}.sky"]
    return plan


def _bar(items, desc: str, enabled: bool, total: int | None = None):
    """A tqdm progress bar (stderr) or the plain iterable."""
    if not enabled:
        return items if items is not None else None
    from tqdm import tqdm

    if items is None:
        return tqdm(total=total, desc=desc, unit="hour", leave=False)
    return tqdm(items, desc=desc, unit="scenario", leave=False)


def reflection_notes(project: Project) -> dict[str, str]:
    """Per scenario, how ground-reflected light is handled (for reports)."""
    out = {}
    for sc in project.scenarios:
        if sc.reflection == "calculated":
            out[sc.name] = "calculated: " + reflection_choice(project, sc).describe()
        else:
            out[sc.name] = "traced: sun → street → façade through the crown model"
    return out
