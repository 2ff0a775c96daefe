"""The report's section on a crown built from points (``[tree] points``, issue 41 item 2): what
the build manifest records of it (point file and SHA-256, voxel size, leaf area, vertical
profile: :func:`radtree.trees.points_crown.points_record`), the profile figure and the crown
beside its points (:mod:`radtree.report.points_figures`). Shown for the first simulated
scenario whose build has a points crown."""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.report.points_figures import CrownViews, crown_views_plot, profile_plot
from radtree.report.sections import Section

log = logging.getLogger(__name__)


def points_scenario(project: Project, names: list[str]
                    ) -> tuple[Scenario, dict[str, Any]] | None:
    """The first of the simulated scenarios ``names`` whose build manifest records a crown
    from points, with that record (None: none has). A scenario with crown realisations is
    shown by its first (``<name>@1``, the build the report pictures)."""
    from radtree.pipeline.realisations import realisations_of

    for parent in project.scenarios:
        if parent.name not in names:
            continue
        sc = realisations_of(project, parent)[0]
        path = project.build_dir / sc.name / "manifest.json"
        if not path.is_file():
            continue
        try:
            record = json.loads(path.read_text(encoding="utf-8"))["build"].get("points_crown")
        except (OSError, ValueError, KeyError, AttributeError):
            continue
        if record:
            return sc, record
    return None


def crown_views(project: Project, sc: Scenario) -> CrownViews:
    """The points and the built slats of the scenario's first crown, in the crown's frame
    (u, n from the trunk axis, z from the street; :mod:`radtree.report.points_figures`)."""
    from radtree.pipeline.build import built_scene
    from radtree.trees.model import LEAF, TRUNK
    from radtree.trees.points_crown import points_crown_grid
    from radtree.trees.points_hull import crown_centre

    tree = effective_project(project, sc).tree
    grid, crown, _ = points_crown_grid(tree, str(project.source))
    cxy = crown_centre(crown)          # where the crown was placed on its trunk
    points = grid.returns - [cxy[0], cxy[1], 0.0]
    model = built_scene(project, sc).tree
    frame = model.frame

    def local(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
        v = frame.to_local(mesh.vertices) if frame is not None else mesh.vertices
        first = (np.asarray(mesh.owners) == "C1") if mesh.owners is not None else \
            np.ones(len(mesh.faces), bool)
        return v, mesh.faces[first]

    trunk = next(m for m in model.meshes if m.material == TRUNK)
    tv, tf = local(trunk)
    axis = tv[np.unique(tf)][:, :2].mean(axis=0)
    slats: list[np.ndarray] = []
    for m in model.meshes:
        if m.material == LEAF:
            v, f = local(m)
            slats.extend(v[f] - [axis[0], axis[1], 0.0])
    return CrownViews(points, slats, grid.size_m)


def points_crown_data(project: Project, out: Path, table: pd.DataFrame
                      ) -> dict[str, Any] | None:
    """The section's data and its two figures (written into ``out/figures``), or None when no
    simulated scenario has a crown from points."""
    found = points_scenario(project, list(dict.fromkeys(table["scenario"].astype(str))))
    if found is None:
        return None
    sc, record = found
    views: CrownViews | None = None
    problem = ""
    try:
        views = crown_views(project, sc)
    except Exception as exc:   # the manifest's profile is still shown
        problem = f"the crown beside its points could not be drawn: {type(exc).__name__}: {exc}"
        log.warning("  %s", problem)
    figs = [{"file": "figures/points_profile.png", "alt": "Leaf area vertical profile",
             "caption": profile_plot(record, views, out / "figures" / "points_profile.png")}]
    if views is not None:
        figs.append({"file": "figures/points_crown.png", "alt": "The crown beside its points",
                     "caption": crown_views_plot(views, out / "figures" / "points_crown.png",
                                                 file=str(record["file"]))})
    prof = record["profile"]
    rows = [{"z": f"{lo:.2f}–{hi:.2f}", "area": f"{a:.2f}", "per_m": f"{pm:.2f}"}
            for lo, hi, a, pm in zip(prof["z_bottom_m"], prof["z_top_m"],
                                     prof["leaf_area_m2"], prof["leaf_area_m2_per_m"])
            if a > 0]
    return {"scenario": sc.name, "file": str(record["file"]),
            "sha256": str(record.get("sha256") or "(file not found at build time)"),
            "voxel": f"{record['voxel_m']:g}", "spacing": f"{record['point_spacing_m']:.2f}",
            "g": f"{record['g_vertical']:.3f}", "leaf_area": f"{record['leaf_area_m2']:.1f}",
            "figures": figs, "rows": rows, "problem": problem}


def points_sections(project: Project, out: Path, table: pd.DataFrame) -> list[Section]:
    """The crown-from-points section when a simulated scenario has one (else none)."""
    if not any(effective_project(project, sc).tree.points is not None
               for sc in project.scenarios):   # no crown from points: nothing to read
        return []
    data = points_crown_data(project, out, table)
    if data is None:
        return []
    log.info("  crown from points: profile and side views (scenario %s)", data["scenario"])
    return [Section("points_crown", data, "Crown from points")]
