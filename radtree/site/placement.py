"""Where the street template's studied façade stands: the façade frame's origin and azimuth.

The street canyon (:mod:`radtree.site.street`) is built in the façade frame (u along the
façade, n out of it towards the street, z up; :class:`radtree.site.frame.FacadeFrame`). Its
origin (u = 0, n = 0: the middle of the façade's foot) and the way it looks come from:

1. ``[street] facade_line = [[x1, y1], [x2, y2]]`` when given — metres in the site frame
   (x east, y north from the site origin ``[site] latitude, longitude``: the local frame the
   inventory is converted to; with ``[site] crs = "local"`` the inventory's own
   coordinates). The façade plane runs through the line and looks to the **right** of
   x1 → x2 (as the edge of a footprint listed counter-clockwise); the origin is the line's
   midpoint and the azimuth the line's (``facade_azimuth_deg`` may be left out, or must
   agree within 1°). Hand-written and inventory projects alike.
2. An inventory without buildings and without a line: the façade looks
   ``facade_azimuth_deg`` and is placed behind the trees — ``[tree.crown]
   trunk_distance_m`` (the row template's trunk-to-façade distance, default 3 m) behind the
   trunk nearest to it, centred along the street on the trunks' mean — never through the
   trees' centroid (the site origin). The build prints where it put it, as a
   ``facade_line`` to copy into ``[street]`` and edit.
3. Otherwise the façade's foot passes through the site origin (the hand-written street).

With buildings (``[site] buildings``) every selected building face is a façade of its own
(:mod:`radtree.site.buildings`): nothing here applies.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from radtree.config import Project
from radtree.config.schema import line_azimuth
from radtree.site.frame import FacadeFrame

Line = tuple[tuple[float, float], tuple[float, float]]
#: the automatic placement's note starts so (``radtree build`` prints it)
NOTE_PREFIX = "Façade placed"


def line_frame(line: Line) -> FacadeFrame:
    """The façade frame of ``facade_line``: origin at its midpoint, looking to its right."""
    (x1, y1), (x2, y2) = line
    return FacadeFrame(azimuth_deg=line_azimuth(line), origin_x=0.5 * (x1 + x2),
                       origin_y=0.5 * (y1 + y2))


def frame_line(frame: FacadeFrame, length_m: float) -> Line:
    """The ``facade_line`` (site frame, m) of a façade frame and street length: the inverse of
    :func:`line_frame`."""
    ends = frame.to_world(np.array([[length_m / 2.0, 0.0, 0.0], [-length_m / 2.0, 0.0, 0.0]]))
    return ((float(ends[0, 0]), float(ends[0, 1])), (float(ends[1, 0]), float(ends[1, 1])))


def behind_trees(azimuth_deg: float, xy: Sequence[tuple[float, float]],
                 trunk_distance_m: float) -> FacadeFrame:
    """A façade looking ``azimuth_deg``, ``trunk_distance_m`` behind the trunk nearest to it,
    centred along it on the trunks' mean (trunks at ``xy``, site frame, m)."""
    turned = FacadeFrame(azimuth_deg=azimuth_deg)
    local = turned.to_local(np.column_stack([np.asarray(xy, float), np.zeros(len(xy))]))
    u0 = float(local[:, 0].mean())
    n0 = float(local[:, 1].min()) - trunk_distance_m
    x0, y0, _ = turned.to_world(np.array([u0, n0, 0.0]))
    return FacadeFrame(azimuth_deg=azimuth_deg, origin_x=float(x0), origin_y=float(y0))


def placement_note(project: Project, frame: FacadeFrame) -> str:
    """Where the automatic placement put the façade, as a ``facade_line`` to copy."""
    (x1, y1), (x2, y2) = frame_line(frame, project.street.length_m)
    return (f"{NOTE_PREFIX} {project.tree.crown.trunk_distance_m:g} m "
            f"([tree.crown] trunk_distance_m) behind the trunk nearest to it, looking "
            f"{frame.azimuth_deg:g}° (street.facade_azimuth_deg): to place it yourself, set "
            f"[street] facade_line = [[{x1:.2f}, {y1:.2f}], [{x2:.2f}, {y2:.2f}]] (site frame, "
            "m; the façade looks to the right of the first point → the second)")


def facade_frame(project: Project) -> FacadeFrame:
    """The studied façade's frame of a street-template project (module text: 1–3)."""
    st = project.street
    if st.facade_line is not None:
        return line_frame(st.facade_line)
    d = project.district
    if d is not None and d.trees is not None and d.buildings is None:
        from radtree.site.district import load_district

        frame = load_district(project).street_frame
        assert frame is not None
        return frame
    return FacadeFrame(azimuth_deg=st.facade_azimuth_deg)
