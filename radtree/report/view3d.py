"""The report's interactive 3-D view: crowns, buildings and sensor grids coloured by illuminance.

``report/view3d.html`` is one self-contained page — a small WebGL viewer
(``templates/view3d.html.j2``, no library: plotly's 4.6 MB bundle alone broke the report's
2 MB budget, issue 38) with the scene inline as quantised triangles — no network, no CDN,
opened from the report folder and embedded in ``index.html``. The scene
of every simulated scenario that has a build folder is rebuilt
(:func:`radtree.pipeline.assemble.make_scene`): what all
scenarios share (street, rooms, glazing) is drawn once; each scenario's crown meshes and its
grids, coloured by the results table's ``lux`` at the shown hour, are toggled by one button per
scenario. Meshes are coloured like the glTF export (:func:`radtree.export.scene_files.
material_rgba`); the scene keeps at most :data:`TRIANGLE_BUDGET` triangles, each mesh an
even subset in proportion to its size (dense slat crowns are thinned), and the section says so. The colour scale is logarithmic in
lux (rooms and façades differ by orders of magnitude), shared by all scenarios, from the 2nd to
the 98th percentile of the shown values.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.fileio import write_text
from radtree.scene import Mesh, Scene

GROUND_MARGIN_M = 3.0
"""The ground is drawn as a light, half-transparent quad reaching this far beyond the rest."""
SHELL_OPACITY = 0.45
"""Opaque surfaces are drawn half-transparent so the grids inside rooms show."""
VIEW_FILE = "view3d.html"
DIV_ID = "radtree-view3d"


def shown_hour(table: pd.DataFrame) -> str:
    """The hour shown: the middle one of the results' hours (in clock order)."""
    hours = sorted(set(table["time"].astype(str)))
    return hours[len(hours) // 2]


def _cropped_ground(mesh: Mesh, others: np.ndarray) -> Mesh:
    """The ground as one quad at its height around ``others`` (k, 3) points."""
    lo = others[:, :2].min(axis=0) - GROUND_MARGIN_M
    hi = others[:, :2].max(axis=0) + GROUND_MARGIN_M
    z = float(mesh.vertices[:, 2].mean())
    v = np.array([[lo[0], lo[1], z], [hi[0], lo[1], z], [hi[0], hi[1], z], [lo[0], hi[1], z]])
    return Mesh(mesh.name, mesh.material, v, np.array([[0, 1, 2], [0, 2, 3]]))


def _display(scene: Scene, mesh: Mesh, others: np.ndarray) -> tuple[Mesh, list[int]]:
    from radtree.export.scene_files import material_rgba

    rgba = list(material_rgba(scene.materials[mesh.material]))
    if mesh.material == scene.ground_material:
        return _cropped_ground(mesh, others), [205, 200, 185, 90]
    if rgba[3] == 255:
        rgba[3] = int(255 * SHELL_OPACITY)
    return mesh, rgba


def write_view(project: Project, table: pd.DataFrame, out: Path) -> dict[str, Any] | None:
    """Write ``out/view3d.html`` (the light viewer: ``templates/view3d.html.j2``, WebGL, no
    library, data inline) and return the section's data (None when no simulated scenario
    has a build folder with geometry — results not made by ``radtree build`` + ``simulate``)."""
    import json

    from radtree.pipeline.build import built_scene
    from radtree.resources import template_environment

    names = list(dict.fromkeys(table["scenario"].astype(str)))
    scenes = {sc.name: built_scene(project, sc).scene for sc in project.scenarios
              if sc.name in names and (project.build_dir / sc.name / "geometry").is_dir()}
    if not scenes:
        return None
    hour = shown_hour(table)
    payload, facts = scene_payload(scenes, table, hour)
    html = template_environment(autoescape=False).get_template("view3d.html.j2").render(
        data=json.dumps(payload, separators=(",", ":")), div_id=DIV_ID)
    write_text(out / VIEW_FILE, html)
    return {"file": VIEW_FILE, **facts,
            "cmax_text": f"{facts['cmax']:.0f}", "cmin_text": f"{facts['cmin']:.0f}",
            "subsampled_text": "; ".join(facts["subsampled"])}


# --------------------------------------------------------------------------- light viewer
#: the light viewer's triangle budget over the whole scene (issue 38: a report ≤ 2 MB): each
#: mesh keeps an even subset of its triangles in proportion to its size
TRIANGLE_BUDGET = 24000


def _quantised(tri: np.ndarray, lo: np.ndarray, span: float) -> str:
    """Triangle corners (k, 3, 3) m as little-endian uint16 over the scene box, base64."""
    import base64

    q = np.clip(np.rint((tri.reshape(-1, 3) - lo) / span * 65535), 0, 65535).astype("<u2")
    return base64.b64encode(q.tobytes()).decode("ascii")


def scene_payload(scenes: dict[str, Scene], table: pd.DataFrame, hour: str
                  ) -> tuple[dict[str, Any], dict[str, Any]]:
    """The light viewer's data (meshes as quantised triangle soups with their colour and
    owning scenario, sensors with log10 lux) and the facts the section states."""
    names = list(scenes)
    keyed = {n: {(m.name, m.material, m.n_triangles) for m in s.solid_meshes()}
             for n, s in scenes.items()}
    common = set.intersection(*keyed.values()) if keyed else set()
    at = table[table["time"].astype(str) == hour]
    shown_lux = np.maximum(at["lux"].to_numpy(float), 1.0)
    lo_l, hi_l = (np.log10(np.percentile(shown_lux, [2, 98])) if len(shown_lux) else (0.0, 1.0))
    hi_l = max(hi_l, lo_l + 0.5)
    others = np.vstack([m.vertices for s in scenes.values() for m in s.solid_meshes()
                        if m.material != s.ground_material and m.n_triangles]
                       + [g.points for s in scenes.values() for g in s.grids.values()])
    first = names[0]
    start = next((n for n in names if len(keyed[n] - common)), first)
    chosen: list[tuple[str | None, Mesh, list[int]]] = []
    for m in scenes[first].solid_meshes():
        if (m.name, m.material, m.n_triangles) in common and m.n_triangles:
            chosen.append((None, *_display(scenes[first], m, others)))
    for name in names:
        for m in scenes[name].solid_meshes():
            if (m.name, m.material, m.n_triangles) not in common and m.n_triangles:
                chosen.append((name, *_display(scenes[name], m, others)))
    allv = np.vstack([others] + [m.vertices for _, m, _ in chosen])
    lo = allv.min(axis=0)
    span = float(max(np.ptp(allv, axis=0).max(), 1e-6))
    total = sum(len(m.faces) for _, m, _ in chosen)
    keep = min(1.0, TRIANGLE_BUDGET / max(total, 1))
    meshes, drawn, thinned = [], 0, []
    for owner, m, rgba in chosen:
        faces = m.faces
        n = max(1, int(round(len(faces) * keep)))
        if n < len(faces):
            faces = faces[np.linspace(0, len(faces) - 1, n).astype(int)]
            if owner is not None:
                thinned.append(f"{owner}: {m.name} {n} of {len(m.faces)}")
        drawn += len(faces)
        meshes.append({"owner": owner, "rgba": rgba, "tri": _quantised(m.vertices[faces], lo,
                                                                        span)})
    points, sensors = [], 0
    for name in names:
        part = at[at["scenario"] == name]
        for gname, rows in part.groupby("grid", sort=False):
            if gname not in scenes[name].grids:
                continue
            rows = rows.sort_values("sensor")
            xyz = rows[["x", "y", "z"]].to_numpy(float)
            points.append({"owner": name, "grid": str(gname),
                           "xyz": [round(float(v), 2) for v in xyz.ravel()],
                           "lux": [round(float(v), 1) for v in rows["lux"]]})
            sensors += len(rows)
    focus = np.vstack([others.min(axis=0), others.max(axis=0)])   # buildings, crowns, grids
    payload = {"scenarios": names, "start": start, "hour": hour, "lo": lo.tolist(),
               "span": span, "centre": focus.mean(axis=0).round(3).tolist(),
               "extent": float(max(np.ptp(focus, axis=0).max(), 1e-3)), "meshes": meshes, "points": points, "log_lo": float(lo_l),
               "log_hi": float(hi_l)}
    facts = {"scenarios": names, "start": start, "hour": hour, "triangles": drawn,
             "sensors": sensors, "subsampled": thinned, "cmin": 10.0 ** lo_l,
             "cmax": 10.0 ** hi_l}
    return payload, facts
