"""Write the SYNTHETIC Mendoza district of this example: data/buildings.geojson and
data/trees.geojson (longitude/latitude, WGS 84).

Not surveyed data: a plausible layout of central Mendoza (Argentina) — an east–west street and
a north–south cross street, both 20 m between façades, lined on their sidewalks by street
trees 4 m from the façades (the city's irrigated tree rows along the acequias), and twelve
buildings of 2–6 storeys in four quarter blocks. Species: white mulberry (Morus alba, the
study's tree), London plane (Platanus × acerifolia), ash (Fraxinus excelsior) and chinaberry
(Melia azedarach), the four Mendoza species of the reference study; sizes are typical
mature street-tree sizes, jittered (seeded) tree by tree.

    python examples/district/make_district.py [--trees 60] [--out examples/district/data]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
from pyproj import Transformer

ORIGIN = (-32.8895, -68.8458)   # latitude, longitude: central Mendoza
HALF_STREET = 10.0              # façades 10 m either side of a street axis
TREE_LINE = 6.0                 # trees 4 m in front of the façades
#: (height m, crown diameter m, crown base m) of each species, before jitter
SPECIES = {
    "morus_alba": (9.0, 6.5, 2.8),
    "platanus_x_acerifolia": (13.0, 7.0, 3.5),
    "fraxinus_excelsior": (11.0, 6.0, 3.0),
    "melia_azedarach": (7.5, 5.5, 2.5),
}


def buildings() -> list[dict]:
    """Twelve footprints (local metres): three per quarter block along the east–west street."""
    rng = np.random.default_rng(7)
    out = []
    k = 0
    for sx in (-1, 1):
        for sy in (-1, 1):
            for i in range(3):
                x0, x1 = HALF_STREET + 30.0 * i, HALF_STREET + 30.0 * (i + 1)
                y0, y1 = HALF_STREET, HALF_STREET + float(rng.uniform(16, 24))
                ring = [(sx * x0, sy * y0), (sx * x1, sy * y0), (sx * x1, sy * y1),
                        (sx * x0, sy * y1)]
                storeys = int(rng.integers(2, 7))
                k += 1
                out.append({"id": f"B{k:02d}", "ring": ring, "height_m": 3.2 * storeys,
                            "storeys": storeys,
                            "facade_reflectance": round(float(rng.uniform(0.3, 0.75)), 2),
                            "window_to_wall": round(float(rng.uniform(0.2, 0.5)), 2)})
    return out


def tree_positions(n: int) -> list[tuple[float, float]]:
    """``n`` trunk positions spread evenly along the four sidewalk lines of each street."""
    lines = []
    for s in (-1, 1):   # east–west street, both sidewalks, both sides of the crossing
        lines += [((12.0, s * TREE_LINE), (98.0, s * TREE_LINE)),
                  ((-12.0, s * TREE_LINE), (-98.0, s * TREE_LINE))]
    for s in (-1, 1):   # north–south street
        lines += [((s * TREE_LINE, 14.0), (s * TREE_LINE, 40.0)),
                  ((s * TREE_LINE, -14.0), (s * TREE_LINE, -40.0))]
    lengths = np.array([math.dist(a, b) for a, b in lines])
    per = np.maximum(1, np.round(n * lengths / lengths.sum()).astype(int))
    while per.sum() > n:
        per[np.argmax(per)] -= 1
    while per.sum() < n:
        per[np.argmin(per / lengths)] += 1
    out = []
    for (a, b), m in zip(lines, per):
        for t in (np.arange(m) + 0.5) / m:
            out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))
    return out


def trees(n: int) -> list[dict]:
    rng = np.random.default_rng(11)
    names = list(SPECIES)
    out = []
    for i, (x, y) in enumerate(tree_positions(n)):
        sp = names[int(rng.integers(0, len(names)))] if i % 3 else "morus_alba"
        h, d, base = SPECIES[sp]
        jit = float(rng.uniform(0.9, 1.1))
        out.append({"id": f"T{i + 1:03d}", "x": x, "y": y, "species": sp,
                    "height_m": round(h * jit, 2), "crown_diameter_m": round(min(7.0, d * jit), 2),
                    "crown_base_m": round(base * float(rng.uniform(0.95, 1.05)), 2)})
    return out


def to_lonlat(x: float, y: float) -> list[float]:
    lat0, lon0 = ORIGIN
    t = Transformer.from_crs(f"+proj=tmerc +lat_0={lat0!r} +lon_0={lon0!r} +k=1 +x_0=0 +y_0=0 "
                             "+ellps=WGS84 +units=m +no_defs", "EPSG:4326", always_xy=True)
    lon, lat = t.transform(x, y)
    return [round(lon, 8), round(lat, 8)]


def write(out: Path, n_trees: int) -> None:
    out.mkdir(parents=True, exist_ok=True)
    bfeat = [{"type": "Feature", "properties": {k: v for k, v in b.items() if k != "ring"},
              "geometry": {"type": "Polygon", "coordinates": [
                  [to_lonlat(*p) for p in [*b["ring"], b["ring"][0]]]]}} for b in buildings()]
    tfeat = [{"type": "Feature", "properties": {k: v for k, v in t.items() if k not in "xy"},
              "geometry": {"type": "Point", "coordinates": to_lonlat(t["x"], t["y"])}}
             for t in trees(n_trees)]
    note = "SYNTHETIC Mendoza district (radtree examples/district/make_district.py), not survey data"
    for name, feats in (("buildings", bfeat), ("trees", tfeat)):
        (out / f"{name}.geojson").write_text(json.dumps(
            {"type": "FeatureCollection", "name": note, "features": feats}, indent=1) + "\n")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=64)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "data")
    args = ap.parse_args()
    write(args.out, args.trees)
    print(f"wrote {args.out}/buildings.geojson (12 buildings), trees.geojson ({args.trees} trees)")
