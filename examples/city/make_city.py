"""Write a SYNTHETIC city district for this example: data/buildings.geojson and
data/trees.geojson in the local frame (``[site] crs = "local"``: x east, y north, metres from
the site origin).

Not surveyed data: a seeded, plausible grid city in the manner of central Mendoza (Argentina):
``--blocks`` × ``--blocks`` blocks of 80 m (east–west) × 60 m (north–south) between streets 20 m
wide (façade to façade), each block four buildings of 2–6 storeys (3.2 m each) that share
their inner walls, so that only the street façades are sensed ([site] facades = "street").
``--trees`` street trees stand evenly along every block's sidewalks, 4.5 m in front of the
façades and at least 6 m from the block corners, species drawn (seeded) from the four Mendoza
species of the reference study (mulberry, London plane, ash, chinaberry) with typical mature
street-tree sizes, jittered ±10 % tree by tree (crown diameter ≤ 7 m, so a crown stays 1 m
clear of the façade). With the default 5 × 5 blocks: 100 buildings, ≈ 7 000 m of street
front; 1 000 trees are one every ≈ 6.7 m.

The same ``--seed`` and arguments write the same files byte for byte. Time and memory at
250 / 500 / 1 000 trees, one process against Dask, and the design for 100 workers:
``benchmarks/city.py``.

    python examples/city/make_city.py [--trees 1000] [--blocks 5] [--seed 1] [--out DIR]

``--out`` is the data folder, or a project folder (then this example's radtree.toml and
weather file are copied into it and the data go to DIR/data).
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
from pathlib import Path

import numpy as np

BLOCK_X, BLOCK_Y, STREET = 80.0, 60.0, 20.0
STOREY_M = 3.2
TREE_LINE = 4.5       # trunks this far in front of the façades (m)
CORNER_CLEAR = 6.0    # no trunk closer than this to a block corner (m)
#: (height m, crown diameter m, crown base m) of each species, before jitter (the values of
#: examples/district/make_district.py)
SPECIES = {
    "morus_alba": (9.0, 6.5, 2.8),
    "platanus_x_acerifolia": (13.0, 7.0, 3.5),
    "fraxinus_excelsior": (11.0, 6.0, 3.0),
    "melia_azedarach": (7.5, 5.5, 2.5),
}
HERE = Path(__file__).resolve().parent


def block_origins(blocks: int) -> list[tuple[float, float]]:
    """South-west corners of the blocks, the grid centred on the origin."""
    w = blocks * BLOCK_X + (blocks - 1) * STREET
    h = blocks * BLOCK_Y + (blocks - 1) * STREET
    return [(-w / 2 + i * (BLOCK_X + STREET), -h / 2 + j * (BLOCK_Y + STREET))
            for j in range(blocks) for i in range(blocks)]


def buildings(blocks: int, rng: np.random.Generator) -> list[dict]:
    """Four footprints per block (counter-clockwise rings), split at a jittered point."""
    out = []
    for bi, (x0, y0) in enumerate(block_origins(blocks)):
        xm = x0 + BLOCK_X * float(rng.uniform(0.4, 0.6))
        ym = y0 + BLOCK_Y * float(rng.uniform(0.4, 0.6))
        xs, ys = (x0, xm, x0 + BLOCK_X), (y0, ym, y0 + BLOCK_Y)
        for q in range(4):
            i, j = q % 2, q // 2
            ring = [(xs[i], ys[j]), (xs[i + 1], ys[j]), (xs[i + 1], ys[j + 1]),
                    (xs[i], ys[j + 1])]
            storeys = int(rng.integers(2, 7))
            out.append({"id": f"B{bi + 1:02d}{'abcd'[q]}",
                        "ring": [(round(x, 3), round(y, 3)) for x, y in ring],
                        "height_m": round(STOREY_M * storeys, 2), "storeys": storeys,
                        "facade_reflectance": round(float(rng.uniform(0.3, 0.75)), 2),
                        "window_to_wall": round(float(rng.uniform(0.2, 0.5)), 2)})
    return out


def tree_lines(blocks: int) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The sidewalk lines (TREE_LINE in front of each block side, corners kept clear)."""
    lines = []
    for x0, y0 in block_origins(blocks):
        x1, y1 = x0 + BLOCK_X, y0 + BLOCK_Y
        lines += [((x0 + CORNER_CLEAR, y0 - TREE_LINE), (x1 - CORNER_CLEAR, y0 - TREE_LINE)),
                  ((x1 + TREE_LINE, y0 + CORNER_CLEAR), (x1 + TREE_LINE, y1 - CORNER_CLEAR)),
                  ((x1 - CORNER_CLEAR, y1 + TREE_LINE), (x0 + CORNER_CLEAR, y1 + TREE_LINE)),
                  ((x0 - TREE_LINE, y1 - CORNER_CLEAR), (x0 - TREE_LINE, y0 + CORNER_CLEAR))]
    return lines


def tree_positions(n: int, blocks: int) -> list[tuple[float, float]]:
    """``n`` trunks spread over the sidewalk lines in proportion to their lengths."""
    lines = tree_lines(blocks)
    lengths = np.array([math.dist(a, b) for a, b in lines])
    per = np.floor(n * lengths / lengths.sum()).astype(int)
    rest = n - int(per.sum())
    per[np.argsort(-(n * lengths / lengths.sum() - per), kind="stable")[:rest]] += 1
    out = []
    for (a, b), m in zip(lines, per):
        for t in (np.arange(m) + 0.5) / max(m, 1):
            out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))
    return out


def trees(n: int, blocks: int, rng: np.random.Generator) -> list[dict]:
    names = list(SPECIES)
    out = []
    for i, (x, y) in enumerate(tree_positions(n, blocks)):
        sp = names[int(rng.integers(0, len(names)))]
        h, d, base = SPECIES[sp]
        jit = float(rng.uniform(0.9, 1.1))
        out.append({"id": f"T{i + 1:04d}", "x": round(x, 3), "y": round(y, 3), "species": sp,
                    "height_m": round(h * jit, 2),
                    "crown_diameter_m": round(min(7.0, d * jit), 2),
                    "crown_base_m": round(base * float(rng.uniform(0.95, 1.05)), 2)})
    return out


def write(out: Path, n_trees: int, blocks: int = 5, seed: int = 1) -> tuple[int, int]:
    """Write the two GeoJSON files into ``out``; returns (buildings, trees)."""
    rng = np.random.default_rng(seed)
    bs = buildings(blocks, rng)
    ts = trees(n_trees, blocks, np.random.default_rng([seed, 1]))
    out.mkdir(parents=True, exist_ok=True)
    bfeat = [{"type": "Feature", "properties": {k: v for k, v in b.items() if k != "ring"},
              "geometry": {"type": "Polygon",
                           "coordinates": [[list(p) for p in [*b["ring"], b["ring"][0]]]]}}
             for b in bs]
    tfeat = [{"type": "Feature", "properties": {k: v for k, v in t.items() if k not in "xy"},
              "geometry": {"type": "Point", "coordinates": [t["x"], t["y"]]}} for t in ts]
    note = "SYNTHETIC grid city (radtree examples/city/make_city.py), not survey data"
    for name, feats in (("buildings", bfeat), ("trees", tfeat)):
        (out / f"{name}.geojson").write_text(json.dumps(
            {"type": "FeatureCollection", "name": note, "features": feats}) + "\n")
    return len(bs), len(ts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=1000)
    ap.add_argument("--blocks", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=HERE / "data")
    args = ap.parse_args()
    data = args.out
    if args.out.resolve() != (HERE / "data").resolve() and args.out.name != "data":
        args.out.mkdir(parents=True, exist_ok=True)   # a project folder
        shutil.copy(HERE / "radtree.toml", args.out / "radtree.toml")
        data = args.out / "data"
        data.mkdir(exist_ok=True)
        shutil.copy(HERE / "data" / "direct_normal_illuminance.csv", data)
    nb, nt = write(data, args.trees, args.blocks, args.seed)
    print(f"wrote {data}/buildings.geojson ({nb} buildings), trees.geojson ({nt} trees)")


if __name__ == "__main__":
    main()
