"""The golden result tables: reduced, seeded runs of the shipped examples.

``python -m tests.golden_cases`` (from the repository root) rewrites ``tests/golden/*.csv``;
``tests/test_golden.py`` regenerates the same tables and compares them to the stored text to the
last printed digit (10 significant digits). A change that moves numbers on purpose rewrites the
golden files in its own commit and says why.

Reductions (to stay quick in CI, identical in the generator and the test): scenario F with 2
crown realisations; NumPy: two hours (10:30 and 13:30; the dense façade map at 13:30), 256 rays
per sensor; Radiance: 13:30 only, ``-ad 64``, no dense map; the office block at 13:30 with
``-ad 128`` / 128 rays per sensor.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pandas as pd

from tests.conftest import drop_photo_scenarios

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden"
FLOAT_FORMAT = "%.10g"
KEYS = ["scenario", "time", "grid", "sensor"]
VALUES = ["lux", "lux_stderr", "lux_traced", "lux_reflected_calc"]

MENDOZA_OVERRIDES = {
    "site.hours": ["10:30", "13:30"],
    "sensors.dense_hours": ["13:30"],
    "engine.rays": 256,
    "engine.dense_rays": 256,   # the map with the sensors' paths, as before dense_rays
    "engine.seed": 1,
}
# Radiance: one hour, -ad 64 (deep -ab runs cost ~ad²), no dense map
MENDOZA_RADIANCE_OVERRIDES = {
    "site.hours": ["13:30"],
    "sensors.dense_grid": False,
    "engine.ad": 64,
}
OFFICE_OVERRIDES = {
    "site.hours": ["13:30"],
    "engine.ad": 128,
    "engine.rays": 128,
    "engine.seed": 1,
}


def _copy(example: str, dst: Path) -> Path:
    src = ROOT / "examples" / example
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns(
        "build", "results", "report", "diagnose", "sweep"))
    text = (dst / "radtree.toml").read_text()
    # scenario F: 2 crown realisations instead of 8
    text = text.replace('"louvers.realisations" = 8', '"louvers.realisations" = 2')
    # ... traced with the reduced rays per sensor, not F's own engine.rays switch
    text = text.replace(', "engine.rays" = 1024 }', ' }')
    # the photo-derived scenarios (A-photo, C-photo, F-photo) are checked by
    # tests/test_photo_crowns.py, not here: the golden tables hold A–F
    text = drop_photo_scenarios(text)
    (dst / "radtree.toml").write_text(text)
    return dst


def _tidy(table: pd.DataFrame) -> pd.DataFrame:
    cols = KEYS + [c for c in VALUES if c in table.columns]
    out = table[cols].copy()
    out["scenario"] = out["scenario"].astype(str)
    out["time"] = out["time"].astype(str)
    return out.sort_values(KEYS).reset_index(drop=True)


def mendoza_table(engine: str, workdir: Path) -> pd.DataFrame:
    """The reduced Mendoza results table (every scenario) with one engine."""
    from radtree.config import load_project
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    overrides = dict(MENDOZA_OVERRIDES)
    if engine == "radiance":
        overrides.update(MENDOZA_RADIANCE_OVERRIDES)
    proj = load_project(_copy("mendoza-street", workdir / f"mendoza-{engine}"),
                        overrides=overrides)
    out = simulate_project(proj, options=RunOptions(engine=engine, fresh=True))
    assert out is not None
    return _tidy(out.table)


def office_summary(engine: str, workdir: Path) -> pd.DataFrame:
    """The reduced office block's hourly summary (results/summary.csv) with one engine."""
    from radtree.config import load_project
    from radtree.office_summary import write_summary
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    proj = load_project(_copy("office-block", workdir / f"office-{engine}"),
                        overrides=OFFICE_OVERRIDES)
    # the summary reads the illuminance only: no tree attribution (simulate --no-tree-impact)
    simulate_project(proj, options=RunOptions(engine=engine, fresh=True, tree_impact=False))
    path = write_summary(proj, maps=False)
    return pd.read_csv(path, dtype={"time": str})


CASES = {
    "mendoza_numpy": lambda d: mendoza_table("numpy", d),
    "mendoza_radiance": lambda d: mendoza_table("radiance", d),
    "office_numpy": lambda d: office_summary("numpy", d),
    "office_radiance": lambda d: office_summary("radiance", d),
}


def as_text(table: pd.DataFrame) -> str:
    return table.to_csv(index=False, float_format=FLOAT_FORMAT, lineterminator="\n")


def main() -> None:
    GOLDEN.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="radtree-golden-") as tmp:
        for name, make in CASES.items():
            text = as_text(make(Path(tmp)))
            (GOLDEN / f"{name}.csv").write_text(text)
            print(f"{name}: {text.count(chr(10)) - 1} rows → {GOLDEN / (name + '.csv')}")


if __name__ == "__main__":
    main()
