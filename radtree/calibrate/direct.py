"""Calibrate a crown model to a target permeability by straight-ray tracing through its meshes.

**Permeability** (as used here): the *direct* (specular, undeviated) transmission of the crown
as seen by the façade sensors — for each sensor of the façade circle, the cosine-weighted mean
over the hemisphere it faces (the directions a vertical illuminance sensor integrates, each
weighted by the cosine to the sensor normal, i.e. for a uniformly bright surrounding) of the
product, over every crown surface the straight ray crosses, of that surface's specular
transmittance (holes and open air pass with 1, opaque sheets and the trunk with 0); then the
mean over the sensors. Only crown meshes are traced (street, façades and ground are left out).
Diffuse transmission and all reflections are **excluded**: a homogeneous (purely diffuse) crown
has direct permeability 0 by this definition and is set analytically instead. The measured
canopy permeability (5–6 % in the study: under-crown / unobstructed vertical illuminance) also
contains diffusely transmitted and reflected light, so a crown calibrated this way passes at
least the target once scattering is simulated.

Louvers: the layer count and the cover fraction (slat density) are chosen. For each layer count
N the analytic cover is f_N = (1 − target^(1/N)) / (1 − T_s); the configured N is kept if f_N is
in (0, 1], otherwise the N whose f_N is closest to the configured cover. Then f is corrected
with the traced permeability (τ ← τ·(target/traced)^(1/N)) until within ``tolerance``.
Perforated (random gaps): the openness is corrected the same way. Every build tried is listed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from radtree.config import Project, load_project
from radtree.errors import ConfigError, RadtreeError
from radtree.fileio import write_text
from radtree.sensor_grid import facade_circle
from radtree.site.frame import FacadeFrame
from radtree.tomlout import value_text
from radtree.trees.build import build_crown
from radtree.trees.geometry import GOLDEN_ANGLE, fibonacci_cosine_directions
from radtree.trees.homogeneous import shell_transmittance
from radtree.trees.louvers import required_cover
from radtree.trees.model import TreeModel
from radtree.trees.raycast import DirectTracer

PERMEABILITY_DEFINITION = (
    "direct (specular) crown transmission seen by the façade sensors: cosine-weighted over "
    "each sensor's hemisphere, product of the specular transmittances of the crown surfaces "
    "crossed, mean over the sensors; diffuse transmission and reflections excluded")


@dataclass
class Candidate:
    """One build tried: its parameters, the analytic and the traced permeability."""

    parameters: dict[str, float]
    analytic: float
    traced: float | None
    slats: int = 0


@dataclass
class CalibrationResult:
    model: str
    form: str
    target: float
    target_source: str
    parameters: dict[str, Any]
    achieved: float
    candidates: list[Candidate] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    written: Path | None = None
    reached: bool = True

    @property
    def section(self) -> str:
        return f"tree.{self.model}"

    def table(self) -> str:
        """The candidates as a plain-text table."""
        keys: list[str] = []
        for c in self.candidates:
            for k in c.parameters:
                if k not in keys:
                    keys.append(k)
        head = [*keys, "analytic", "traced", "slats"]
        rows = [head]
        for c in self.candidates:
            rows.append([_fmt(c.parameters.get(k)) for k in keys]
                        + [f"{100 * c.analytic:.3f} %",
                           "—" if c.traced is None else f"{100 * c.traced:.3f} %",
                           str(c.slats) if c.slats else ""])
        widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
        return "\n".join("  ".join(v.rjust(w) for v, w in zip(r, widths)) for r in rows)


def _fmt(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.4f}"
    return str(v)


def sensor_rays(project: Project, frame: FacadeFrame, directions: int = 2048
                ) -> tuple[np.ndarray, np.ndarray]:
    """Origins and cosine-weighted directions for every sensor of the façade circle."""
    grid = facade_circle(project.sensors, frame)
    origins, dirs = [], []
    for i, (p, nrm) in enumerate(zip(grid.points, grid.normals)):
        d = fibonacci_cosine_directions(directions, nrm, rotation=GOLDEN_ANGLE * i * 7.0)
        dirs.append(d)
        origins.append(np.repeat(p[None, :], directions, axis=0))
    return np.vstack(origins), np.vstack(dirs)


def sensor_permeability(model: TreeModel, project: Project, frame: FacadeFrame,
                        directions: int = 2048) -> float:
    """Direct permeability of a built crown as seen by the façade sensors (module docstring)."""
    origins, dirs = sensor_rays(project, frame, directions)
    return float(np.mean(DirectTracer(model.meshes, model.materials).transmission(origins, dirs)))


def _target(project: Project, model: str, target: float | None, photo_openness: bool
            ) -> tuple[float, str]:
    if photo_openness:
        if target is not None:
            raise RadtreeError("give either --target or --photo-openness, not both")
        perf = project.tree.perforated
        if perf.photo is None:
            raise ConfigError("--photo-openness needs a photo (tree.perforated.photo)",
                              source=str(project.source), field="tree.perforated.photo")
        from radtree.trees.perforated import photo_gap_pattern

        pattern = photo_gap_pattern(perf, str(project.source))
        return pattern.openness, f"openness of {Path(perf.photo).name}"
    if target is None:
        return project.tree.homogeneous.permeability, "tree.homogeneous.permeability"
    return float(target), "--target"


def calibrate(project: Project, *, model: str = "louvers", target: float | None = None,
              form: str | None = None, photo_openness: bool = False, directions: int = 2048,
              tolerance: float = 0.001, max_layers: int = 12, max_builds: int = 16
              ) -> CalibrationResult:
    """Choose the crown parameters that give the target permeability (see module docstring)."""
    goal, source = _target(project, model, target, photo_openness)
    if not 0.0 < goal < 1.0:
        raise RadtreeError(f"target permeability must be between 0 and 1, got {goal}")
    form = form or project.tree.form
    frame = FacadeFrame(project.street.facade_azimuth_deg)
    if model == "louvers":
        return _calibrate_louvers(project, goal=goal, source=source, form=form, frame=frame,
                                  directions=directions, tolerance=tolerance,
                                  max_layers=max_layers, max_builds=max_builds)
    if model == "perforated":
        return _calibrate_perforated(project, goal=goal, source=source, form=form, frame=frame,
                                     directions=directions, tolerance=tolerance,
                                     max_builds=max_builds)
    if model == "homogeneous":
        tree = replace(project.tree, homogeneous=replace(project.tree.homogeneous,
                                                         transmittance=None, permeability=goal))
        t, crossings, how = shell_transmittance(tree, form)
        cand = Candidate({"transmittance": t}, t**crossings, None)
        return CalibrationResult(
            model, form, goal, source, {"transmittance": round(t, 6)}, t**crossings, [cand],
            [f"The homogeneous crown is purely diffuse: its direct permeability is 0 by "
             f"definition, so it is set analytically: T {how} = {t:.4f}."])
    raise RadtreeError(f"cannot calibrate model {model!r} (louvers, perforated, homogeneous)")


def _calibrate_louvers(project: Project, *, goal: float, source: str, form: str,
                       frame: FacadeFrame, directions: int, tolerance: float, max_layers: int,
                       max_builds: int) -> CalibrationResult:
    lv = project.tree.louvers
    ts = lv.transmittance * lv.specular_fraction
    if ts >= 1.0:
        raise RadtreeError("slats with specular transmittance 1 cannot filter any light")
    feasible = {n: required_cover(goal, n, ts) for n in range(1, max_layers + 1)}
    feasible = {n: f for n, f in feasible.items() if 0.0 < f <= 1.0}
    if not feasible:
        raise RadtreeError(
            f"no louvers crown of 1–{max_layers} layers reaches a direct permeability of "
            f"{goal:.4f} with slat specular transmittance {ts:.3f} "
            f"(full cover gives {ts**max_layers:.2e} … {ts:.3f})")
    order = sorted(feasible, key=lambda n: (n != lv.layers, abs(feasible[n] - lv.cover_fraction)))
    candidates: list[Candidate] = []
    best: Candidate | None = None
    builds = 0
    notes: list[str] = []
    for n in order[:4]:
        f = feasible[n]
        for _ in range(6):
            if builds >= max_builds:
                break
            tree = replace(project.tree, louvers=replace(lv, layers=n, cover_fraction=f))
            built = build_crown(project, "louvers", form, frame, tree)
            builds += 1
            p = sensor_permeability(built, project, frame, directions)
            cand = Candidate({"layers": n, "cover_fraction": f},
                             built.info["tau_crown_direct"], p, int(built.info["slat_count"]))
            candidates.append(cand)
            if best is None or abs(p - goal) < abs((best.traced or 0.0) - goal):
                best = cand
            if abs(p - goal) <= tolerance:
                break
            tau = 1.0 - f * (1.0 - ts)
            if p <= 0.0:
                f_new = 0.8 * f
            else:
                f_new = (1.0 - tau * (goal / p) ** (1.0 / n)) / (1.0 - ts)
            if f >= 1.0 and f_new >= 1.0:
                notes.append(f"{n} layers: even full cover passes {100 * p:.2f} % (> target).")
                break
            f = float(min(1.0, max(0.01, f_new)))
        if best is not None and best.traced is not None and abs(best.traced - goal) <= tolerance:
            break
    assert best is not None and best.traced is not None
    params = {"layers": int(best.parameters["layers"]),
              "cover_fraction": round(float(best.parameters["cover_fraction"]), 4)}
    reached = abs(best.traced - goal) <= 5.0 * tolerance
    if not reached:
        notes.append(f"Target NOT reached: the closest build is "
                     f"{100 * abs(best.traced - goal):.2f} percentage points from it.")
        if form == "free":
            notes.append("Near-horizontal and downward views from façade sensors cross few "
                         "layers of a free louvers crown (the reference case, first physical check, point 2), "
                         "so density alone cannot bring its direct permeability down to the "
                         "target; the sensor-dome form can.")
    notes.insert(0, f"Louvers ({form} form), slat specular transmittance {ts:.3f}: analytic "
                    "cover per layer count " + ", ".join(f"{n}: {f:.3f}" for n, f in
                                                         sorted(feasible.items())) + ".")
    return CalibrationResult("louvers", form, goal, source, params, best.traced, candidates,
                             notes, reached=reached)


def _calibrate_perforated(project: Project, *, goal: float, source: str, form: str,
                          frame: FacadeFrame, directions: int, tolerance: float,
                          max_builds: int) -> CalibrationResult:
    perf = project.tree.perforated
    if perf.photo is not None:
        raise RadtreeError("the perforated crown is defined by its photo (tree.perforated.photo):"
                           " there is no openness to calibrate; remove the photo to calibrate "
                           "the random gap pattern")
    o = goal
    candidates: list[Candidate] = []
    best: Candidate | None = None
    for _ in range(max_builds):
        tree = replace(project.tree, perforated=replace(perf, openness=o))
        built = build_crown(project, "perforated", form, frame, tree)
        p = sensor_permeability(built, project, frame, directions)
        cand = Candidate({"openness": o}, built.info["hole_fraction"], p)
        candidates.append(cand)
        if best is None or abs(p - goal) < abs((best.traced or 0.0) - goal):
            best = cand
        if abs(p - goal) <= tolerance or p <= 0.0:
            break
        o = float(min(0.999, max(1e-4, o * goal / p)))
        if len(candidates) >= 6:
            break
    assert best is not None and best.traced is not None
    notes = [f"Perforated ({form} form), seeded random gaps: openness is the hole solid-angle "
             "share seen from the camera point; the sensors' cosine-weighted view differs "
             "slightly, hence the correction."]
    reached = abs(best.traced - goal) <= 5.0 * tolerance
    if not reached:
        notes.append(f"Target NOT reached: the closest build is "
                     f"{100 * abs(best.traced - goal):.2f} percentage points from it.")
    return CalibrationResult("perforated", form, goal, source,
                             {"openness": round(float(best.parameters["openness"]), 5)},
                             best.traced, candidates, notes, reached=reached)


# ---------------------------------------------------------------- writing the result
_HEADER = re.compile(r"^\s*\[\s*([A-Za-z0-9_.\-]+)\s*\]\s*(#.*)?$")


def _toml_value(v: Any) -> str:
    """A value as TOML text, floats to 6 decimals (the written calibration)."""
    return value_text(round(v, 6) if isinstance(v, float) else v)


def calibrated_path(project: Project) -> Path:
    """``<name>.calibrated.toml`` beside the project file (never the project file itself)."""
    src = Path(project.source)
    return src.with_name(src.stem + ".calibrated.toml")


def write_calibrated_toml(project: Project, result: CalibrationResult) -> Path:
    """Copy the project file with the calibrated values set; returns the new file's path.

    The user's file is never modified. The copy is checked by loading it before it is moved
    into place.
    """
    src = Path(project.source)
    out = calibrated_path(project)
    if out.resolve() == src.resolve():  # pragma: no cover - calibrated_path never allows it
        raise RadtreeError(f"refusing to overwrite the project file {src}")
    lines = src.read_text(encoding="utf-8").splitlines()
    section = result.section
    start = end = None
    for i, line in enumerate(lines):
        m = _HEADER.match(line)
        if m and start is None and m.group(1) == section:
            start = i
        elif m and start is not None:
            end = i
            break
    stamp = (f"calibrated by radtree calibrate: permeability {result.achieved:.4f} "
             f"(target {result.target:.4f}, {result.target_source})")
    if start is None:
        lines += ["", f"[{section}]  # {stamp}"]
        start, end = len(lines) - 1, len(lines)
    if end is None:
        end = len(lines)
    for key, value in result.parameters.items():
        pat = re.compile(rf"^\s*{re.escape(key)}\s*=")
        new = f"{key} = {_toml_value(value)}  # {stamp}"
        for i in range(start + 1, end):
            if pat.match(lines[i]):
                lines[i] = new
                break
        else:
            insert = end
            while insert - 1 > start and not lines[insert - 1].strip():
                insert -= 1
            lines.insert(insert, new)
            end += 1
    header = [f"# Written by `radtree calibrate` from {src.name} — {result.model} model, "
              f"{result.form} form. Your {src.name} is unchanged.",
              f"# Permeability = {PERMEABILITY_DEFINITION}.", ""]
    text = "\n".join(header + lines) + "\n"
    tmp = out.with_name(f".{out.name}.check")
    try:
        write_text(tmp, text)
        load_project(tmp)
    except RadtreeError as exc:
        raise RadtreeError(f"the calibrated project file would not load: {exc}") from exc
    finally:
        if tmp.exists():
            tmp.unlink()
    write_text(out, text)
    result.written = out
    return out


__all__ = ["PERMEABILITY_DEFINITION", "CalibrationResult", "Candidate", "calibrate",
           "calibrated_path", "sensor_permeability", "sensor_rays", "write_calibrated_toml"]
