"""Write the SYNTHETIC airborne tile and footprints of this example (not survey data):
data/street_tile.laz and data/buildings.geojson, both in UTM zone 19S (EPSG:32719) metres.

An east–west street in central Mendoza (Argentina), 20 m between façades, four buildings of
3–5 storeys, and eight street trees on its sidewalks 4 m in front of the façades: radtree's own
volume-louvers crowns (radtree.trees.synthetic_scan, seeded) scanned by radtree's synthetic
airborne scanner (radtree.lidar.scanner: 10 pulses/m², 300 m altitude, one thin beam a pulse),
ground class 2, vegetation 5, roofs 6. The true trees are printed, to compare with what
`radtree lidar segment` finds.

    python examples/lidar-street/make_tile.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from radtree.fileio import write_text
from radtree.lidar.scanner import AlsScan
from radtree.trees.synthetic_scan import StreetTree, scan_street, write_scan

HERE = Path(__file__).resolve().parent
CRS = "EPSG:32719"
ORIGIN = (514400.0, 6360500.0)    # UTM 19S easting, northing of the street axis' west end
BUILDINGS = [  # id, x0, x1, y0, y1 (street-local metres: x east, y north), storeys
    ("B1", -15.0, 15.0, 10.0, 26.0, 4), ("B2", 15.0, 45.0, 10.0, 24.0, 3),
    ("B3", -15.0, 20.0, -26.0, -10.0, 5), ("B4", 20.0, 45.0, -22.0, -10.0, 3)]
STOREY_M = 3.2


def trees() -> list[StreetTree]:
    rng = np.random.default_rng(41)
    out = []
    for i, (x, y) in enumerate([(x, y) for y in (6.0, -6.0) for x in (0.0, 10.0, 20.0, 30.0)]):
        h = float(rng.uniform(8.0, 11.0))
        out.append(StreetTree(f"S{i + 1}", x, y, h, float(rng.uniform(2.6, 3.4)),
                              float(rng.uniform(0.28, 0.36) * h)))
    return out


def box(x0: float, x1: float, y0: float, y1: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    m = trimesh.creation.box(bounds=[[x0, y0, 0.0], [x1, y1, h]])
    return np.asarray(m.vertices), np.asarray(m.faces)


def main() -> None:
    extra = [(*box(x0, x1, y0, y1, n * STOREY_M), 6) for _, x0, x1, y0, y1, n in BUILDINGS]
    street = trees()
    pts, areas, _ = scan_street(street, AlsScan(pulse_density_m2=10.0, seed=41), extra=extra,
                                area=((-15.0, -26.0), (45.0, 26.0)))
    tile = write_scan(pts, HERE / "data" / "street_tile.laz", offset=ORIGIN, crs=CRS)
    feats = []
    for bid, x0, x1, y0, y1, n in BUILDINGS:
        ring = [[x + ORIGIN[0], y + ORIGIN[1]] for x, y in
                ((x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0))]
        feats.append({"type": "Feature", "properties": {"id": bid, "height_m": n * STOREY_M,
                                                        "storeys": n},
                      "geometry": {"type": "Polygon", "coordinates": [ring]}})
    doc = {"type": "FeatureCollection", "name": "SYNTHETIC street (radtree examples/"
           "lidar-street/make_tile.py), not survey data",
           "crs": {"type": "name", "properties": {"name": CRS}}, "features": feats}
    write_text(HERE / "data" / "buildings.geojson", json.dumps(doc, indent=1) + "\n")
    print(f"{tile}: {len(pts.xyz)} points; {HERE / 'data' / 'buildings.geojson'}")
    for t in street:
        print(f"{t.id}: x {t.x + ORIGIN[0]:.1f} y {t.y + ORIGIN[1]:.1f} height "
              f"{t.height_m:.2f} m, crown diameter {2 * t.crown_radius_m:.2f} m, base "
              f"{t.crown_base_m:.2f} m, leaf area {areas[t.id]:.1f} m²")


if __name__ == "__main__":
    main()
