"""`radtree report`: tables, figures, CSV outputs and errors, on a synthetic results layout.

The results table is written by hand (scenarios A–E of the study plus a free-standing-crown
scenario F with a Perez sky, 7 hours, the 8 façade sensors and a small dense façade grid on a
façade rotated 15°), so the test runs without any engine in a few seconds. One test at the end
runs a real open-street Radiance simulation and reports it.
"""

from __future__ import annotations

import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.cli.report import report_command
from radtree.config import Project, load_project
from radtree.errors import RadtreeError
from radtree.measurements import load_measured
from radtree.report import build_report
from radtree.report.build import STATISTICS_CONTRACT
from radtree.report.data import facade_coordinates
from radtree.sensor_grid import facade_circle, facade_dense_grid
from radtree.site.frame import FacadeFrame
from radtree.stats import compare

from .conftest import copy_project, needs_radiance

PNG = b"\x89PNG\r\n\x1a\n"
HOURS = ["10:30", "11:30", "12:30", "13:30", "14:30", "15:30", "16:30"]
MEASURED = [1157.0, 1504.0, 1621.0, 1592.0, 1504.0, 1311.0, 1099.0]
# scenario → (model, reflection, factor on the measured value, Monte Carlo stderr or None)
SCENARIOS = {
    "A": ("louvers", "calculated", 1.04, None),
    "B": ("louvers", "traced", 0.78, 9.0),
    "C": ("perforated", "traced", 1.45, None),
    "D": ("perforated", "calculated", 1.20, None),
    "E": ("homogeneous", "traced", 2.10, 14.0),
    "F": ("louvers", "traced", 0.95, 11.0),
}
FREE_SCENARIO = '''
[[scenario]]
name = "F"
model = "louvers"
reflection = "traced"
form = "free"
sky = "perez"
description = "free-standing louvers crowns, clear Perez sky"
'''


# --------------------------------------------------------------------------- fixtures


def make_project(root: Path, measured: bool = True) -> Path:
    p = copy_project(root, replace={r"^facade_azimuth_deg = 0\.0": "facade_azimuth_deg = 15.0",
                                    r"^dense_size_m = .*$": "dense_size_m = 2.0",
                                    r"^dense_spacing_m = .*$": "dense_spacing_m = 0.5"})
    toml = p / "radtree.toml"
    text = toml.read_text()
    if 'name = "F"' not in text:
        text += FREE_SCENARIO
    if not measured:
        text = re.sub(r"^measured = .*$", "", text, flags=re.M)
    toml.write_text(text)
    return p


def write_results(project: Project, hours: list[str] = HOURS) -> pd.DataFrame:
    """A plausible results layout; façade hourly means = factor × measured (+ small noise)."""
    frame = FacadeFrame(azimuth_deg=project.street.facade_azimuth_deg)
    grids = {"facade": facade_circle(project.sensors, frame),
             "facade_map": facade_dense_grid(project.sensors, frame)}
    rng = np.random.default_rng(3)
    measured = dict(zip(HOURS, MEASURED))
    frames = []
    for name, (model, reflection, factor, se) in SCENARIOS.items():
        phash = project.params_hash(project.scenario(name))
        for t in hours:
            base = factor * measured[t] * (1 + 0.05 * rng.standard_normal())
            for gname, grid in grids.items():
                z = grid.points[:, 2]
                lux = base * (1 + 0.04 * (z - project.sensors.height_m))
                frames.append(pd.DataFrame({
                    "scenario": name, "model": model, "datetime": f"2024-12-22T{t}:00-03:00",
                    "time": t, "grid": gname, "sensor": np.arange(len(grid)), "row": grid.rows,
                    "x": grid.points[:, 0], "y": grid.points[:, 1], "z": z, "lux": lux,
                    "lux_stderr": np.nan if se is None else se,
                    "engine": "radiance" if se is None else "numpy", "params_hash": phash,
                    "lux_traced": lux, "lux_reflected_calc": 0.0, "reflection": reflection,
                }))
    table = pd.concat(frames, ignore_index=True)
    results = project.results_dir
    results.mkdir(parents=True, exist_ok=True)
    table.to_csv(results / "illuminance.csv", index=False)
    pd.DataFrame([{"scenario": n, "engine": "numpy", "preparation_s": 0.12 + i,
                   "geometry_s": 0.5 * i, "tracing_s": 10.0 + 3 * i}
                  for i, n in enumerate(SCENARIOS)]).to_csv(results / "timing.csv", index=False)
    (results / "manifest.json").write_text(json.dumps({
        "radtree_version": "0.1.0", "radiance_version": "RADIANCE 6.0a", "python": "3.11",
        "created": "2024-12-22T12:00:00+00:00", "project": project.name,
        "parameters": project.to_dict(), "seeds": {"engine": 1, "louvers": 1},
        "inputs": {"measured": "measured_vertical_illuminance.csv sha256:abc123"},
        "params_hash": {s.name: project.params_hash(s) for s in project.scenarios},
        "engine": "numpy", "scenarios": list(SCENARIOS)}, default=str))
    conv = []
    for name in ("A", "B"):
        prev = None
        for ab in (1, 2, 3, 4, 6, 8):
            mean = 1400 * (1 - 0.5 ** ab)
            conv.append({"scenario": name, "model": "louvers", "time": "10:30", "ab": ab,
                         "ad": 1024, "facade_mean_lux": mean,
                         "change": None if prev is None else (mean - prev) / prev,
                         "model_recommended_ab": 6})
            prev = mean
    pd.DataFrame(conv).to_csv(results / "convergence.csv", index=False)
    for i, name in enumerate(SCENARIOS):
        folder = project.build_dir / name
        folder.mkdir(parents=True, exist_ok=True)
        form = "free" if name == "F" else "dome"
        (folder / "manifest.json").write_text(json.dumps({"build": {
            "scenario": name, "model": SCENARIOS[name][0], "form": form, "ab": 6,
            "triangles": 1000 + i, "params_hash": project.params_hash(project.scenario(name)),
            "notes": [f"crown reading of {name}: near-opaque leaves in layers"],
            "info": {"slats": 2225 + i, "permeability": 0.055}}}))
    _write_png(project.build_dir / "A" / "model.png")
    return table


def _write_png(path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(1, 1), dpi=40)
    FigureCanvasAgg(fig)
    fig.add_subplot().plot([0, 1], [0, 1])
    fig.savefig(path, format="png")


@pytest.fixture
def project(tmp_path: Path) -> Project:
    p = load_project(make_project(tmp_path / "proj"))
    write_results(p)
    return p


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Project, Path]:
    """One report built for the read-only tests (building takes a few seconds)."""
    p = load_project(make_project(tmp_path_factory.mktemp("report") / "proj"))
    write_results(p)
    write_scan_and_diagnosis(p)
    return p, build_report(p)


def write_scan_and_diagnosis(p: Project) -> None:
    """A permeability scan (results/) and a diagnosis (diagnose/steps.csv) to report."""
    from radtree.calibrate.scan import PermeabilityScan, write_scan

    scan = pd.DataFrame({"value": [0.5, 0.52], "permeability_street": [0.06, 0.073],
                         "permeability_street_se": [2e-4, 2e-4],
                         "permeability_unobstructed": [0.049, 0.06],
                         "permeability_unobstructed_se": [1e-4, 1e-4],
                         "nrmse": [0.2, 0.107], "nmbe": [0.19, 0.056], "r": [0.92, 0.92]})
    write_scan(PermeabilityScan("A", "louvers.transmittance", scan, []), p.results_dir)
    (p.root / "diagnose").mkdir(exist_ok=True)
    (p.root / "diagnose" / "index.html").write_text("<html></html>")
    pd.DataFrame([{"step": 1, "effect": "sky_diffuse", "explained_fraction": 0.9,
                   "strength": 14900.0, "rmse_before": 0.198, "rmse_after": 0.064,
                   "cv_rmse_before": 0.198, "cv_rmse_after": 0.075,
                   "strength_text": "14,900 lx"}]).to_csv(p.root / "diagnose" / "steps.csv",
                                                          index=False)


# --------------------------------------------------------------------------- HTML parsing


class ReportParser(HTMLParser):
    """Tables (id of the wrapper, rows of (tag, classes, text)) and image sources."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: list[dict] = []
        self.images: list[str] = []
        self._wrapper_id: str | None = None
        self._table: dict | None = None
        self._row: list | None = None
        self._cell: list | None = None
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "div" and "tablewrap" in (a.get("class") or ""):
            self._wrapper_id = a.get("id")
        elif tag == "table":
            self._table = {"id": self._wrapper_id, "rows": []}
            self.tables.append(self._table)
        elif tag == "tr" and self._table is not None:
            self._row = []
            self._table["rows"].append(self._row)
        elif tag in ("td", "th") and self._row is not None:
            self._cell = [tag, (a.get("class") or "").split(), ""]
            self._row.append(self._cell)
        elif tag == "img":
            self.images.append(a["src"])

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._cell = None
        elif tag == "tr":
            self._row = None
        elif tag == "table":
            self._table = None

    def handle_data(self, data):
        self.text.append(data)
        if self._cell is not None:
            self._cell[2] += data


def parse(path: Path) -> ReportParser:
    parser = ReportParser()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def number(cell_text: str) -> float | None:
    """The number a numeric cell shows ("1234 ± 12" → 1234); None for "—"."""
    t = cell_text.strip()
    if t == "—":
        return None
    return float(t.split("±")[0].strip())


def table(parser: ReportParser, key: str) -> dict:
    found = [t for t in parser.tables if t["id"] == f"t-{key}"]
    assert found, f"no table {key}: {[t['id'] for t in parser.tables]}"
    return found[0]


def body(t: dict) -> list[list]:
    return [r for r in t["rows"] if r and r[0][0] == "td"]


# --------------------------------------------------------------------------- tests


def test_report_tables_figures_and_pictures(built: tuple[Project, Path]):
    project, index = built
    assert index == project.report_dir / "index.html"
    assert (project.report_dir / "index.md").stat().st_size > 1000
    parser = parse(index)

    # every numeric cell is a number (or "—" for a missing value)
    assert len(parser.tables) >= 10
    for t in parser.tables:
        for row in body(t):
            for _, classes, text in row:
                if "num" in classes:
                    number(text)  # raises if not a number

    hourly = body(table(parser, "hourly"))
    assert [r[0][2] for r in hourly[:7]] == HOURS
    for r in hourly:
        assert len(r) == 2 + len(SCENARIOS)
        assert all(number(c[2]) is not None for c in r[1:]), r
    assert number(hourly[0][1][2]) == MEASURED[0]
    assert "±" in hourly[0][2 + list(SCENARIOS).index("B")][2]  # Monte Carlo error shown

    stats = table(parser, "statistics")
    srows = body(stats)
    assert sorted(r[0][2] for r in srows) == sorted(SCENARIOS)
    for r in srows:
        assert all(number(c[2]) is not None for c in r[3:-1]), r  # last: MC SE, may be "—"
    groups = [r[0][2] for r in stats["rows"] if len(r) == 1 and r[0][0] == "th"]
    assert any("free-standing" in g for g in groups) and any("dome" in g for g in groups)

    for key in ("scenarios", "rows", "rows_between", "timing", "reflection", "convergence",
                "convergence_summary", "provenance", "hashes", "inputs", "parameters",
                "permeability_scan", "diagnose_steps"):
        assert body(table(parser, key)), key
    timing = {r[0][2]: r for r in body(table(parser, "timing"))}
    assert number(timing["C"][5][2]) == pytest.approx(0.12 + 2 + 1.0 + 16.0, abs=0.06)
    rows = body(table(parser, "rows"))
    assert {r[1][2] for r in rows} == {"higher", "intermediate", "lower"}
    assert all(number(r[3][2]) in (1407, 1369, 1409) for r in rows)

    # every image exists and is a non-empty PNG; model picture copied, the others say so
    assert parser.images
    for src in parser.images:
        f = project.report_dir / src
        assert f.is_file(), src
        data = f.read_bytes()
        assert len(data) > 100 and data[:8] == PNG, src
    assert "models/A.png" in parser.images
    for key in ("hourly", "scatter", "facade_map", "facade_map_all", "timing", "convergence"):
        assert f"figures/{key}.png" in parser.images
    assert "permeability_scan.png" in parser.images
    md = (project.report_dir / "index.md").read_text()
    assert "| 0.52 | 7.30 | 6.00 | 0.107 | +0.056 | 0.920 |" in md
    assert "| 1 | sky_diffuse | 14,900 lx | 90 | 0.198 → 0.064 | 0.198 → 0.075 |" in md
    scan = body(table(parser, "permeability_scan"))
    assert [number(r[3][2]) for r in scan] == [0.2, 0.107]
    text = " ".join(parser.text)
    assert text.count("no picture") == len(SCENARIOS) - 1
    assert "crown reading of F" in text  # build notes
    assert "E_refl = ρ(α)·E_ground·F" in text  # reflection handling of the calculated ones
    assert "could not be drawn" not in text


def test_statistics_csv_matches_compare(built: tuple[Project, Path]):
    project, _ = built
    stats = pd.read_csv(project.report_dir / "statistics.csv", dtype={"scenario": str})
    assert list(stats.columns[:len(STATISTICS_CONTRACT)]) == STATISTICS_CONTRACT
    results = pd.read_csv(project.results_dir / "illuminance.csv", dtype={"scenario": str})
    assert project.measured is not None
    measured = load_measured(project.measured)[0]
    expected = compare(results, measured).stats.set_index("scenario")
    got = stats.set_index("scenario")
    assert sorted(got.index) == sorted(expected.index)
    for col in ("rmse", "rmse_low", "rmse_high", "mbe", "r", "r2", "n_hours"):
        np.testing.assert_allclose(got.loc[expected.index, col], expected[col], rtol=1e-12)
    assert (got["n_hours"] == 7).all()
    assert got.loc["F", "form"] == "free" and got.loc["A", "form"] == "dome"
    assert got.loc["A", "reflection"] == "calculated"


def test_hourly_csv(built: tuple[Project, Path]):
    project, _ = built
    hourly = pd.read_csv(project.report_dir / "hourly.csv")
    assert list(hourly.columns[:2]) == ["time", "measured_lux"]
    assert sorted(hourly.columns[2:]) == sorted(SCENARIOS)
    assert list(hourly["time"]) == HOURS
    assert list(hourly["measured_lux"]) == MEASURED
    results = pd.read_csv(project.results_dir / "illuminance.csv", dtype={"scenario": str})
    facade = results[results["grid"] == "facade"]
    mean = facade[(facade["scenario"] == "C") & (facade["time"] == "12:30")]["lux"].mean()
    assert hourly.loc[hourly["time"] == "12:30", "C"].item() == pytest.approx(mean)


def test_without_measurements(tmp_path: Path):
    p = load_project(make_project(tmp_path / "proj", measured=False))
    assert p.measured is None
    write_results(p)
    index = build_report(p)
    parser = parse(index)
    text = " ".join(parser.text)
    assert "No measurements" in text
    stats = pd.read_csv(p.report_dir / "statistics.csv")
    assert stats.empty and list(stats.columns[:len(STATISTICS_CONTRACT)]) == STATISTICS_CONTRACT
    hourly = pd.read_csv(p.report_dir / "hourly.csv")
    assert hourly["measured_lux"].isna().all() and len(hourly) == 7
    assert "figures/scatter.png" not in parser.images
    assert "figures/hourly.png" in parser.images and "figures/facade_map.png" in parser.images
    # the per-row table still compares with the measured per-row daily means
    assert body(table(parser, "rows"))


def test_minimal_results_layout(project: Project):
    """Only illuminance.csv, façade grid only: the report says what is missing."""
    results = pd.read_csv(project.results_dir / "illuminance.csv", dtype={"scenario": str})
    results[results["grid"] == "facade"].drop(columns=["lux_stderr", "reflection"]).to_csv(
        project.results_dir / "illuminance.csv", index=False)
    for name in ("timing.csv", "convergence.csv", "manifest.json"):
        (project.results_dir / name).unlink()
    import shutil

    shutil.rmtree(project.build_dir)
    parser = parse(build_report(project))
    text = " ".join(parser.text)
    assert "No façade map" in text and "no build manifest" in text
    html = (project.report_dir / "index.html").read_text()   # sections without data: absent
    assert 'id="timing"' not in html and 'id="convergence"' not in html
    assert "light not recorded" in text   # no manifest: no weather record, no default string
    assert sorted(parser.images) == ["figures/hourly.png", "figures/scatter.png"]
    stats = pd.read_csv(project.report_dir / "statistics.csv", keep_default_na=False)
    assert list(stats["reflection"]) == [SCENARIOS[n][1] for n in stats["scenario"]]


def test_missing_results_is_a_clear_error(tmp_path: Path):
    p = load_project(make_project(tmp_path / "proj"))
    with pytest.raises(RadtreeError, match=r"no results: run `radtree simulate .*` first"):
        build_report(p)
    assert not p.report_dir.exists()


def test_measured_hour_without_simulation_is_not_dropped(tmp_path: Path):
    p = load_project(make_project(tmp_path / "proj"))
    write_results(p, hours=HOURS[:-1])
    with pytest.raises(RadtreeError, match="measured hour.*without a simulated value.*16:30"):
        build_report(p)
    assert not p.report_dir.exists()


def test_cli_report_replaces_the_folder_whole(project: Project):
    project.report_dir.mkdir()
    (project.report_dir / "stale.txt").write_text("old")
    r = CliRunner().invoke(report_command, [str(project.root)])
    assert r.exit_code == 0, r.output
    assert str(project.report_dir / "index.html") in r.output
    assert "nRMSE" in r.output and "R²" in r.output
    for name in SCENARIOS:
        assert re.search(rf"^\s*{name}\s", r.output, flags=re.M), name
    assert not (project.report_dir / "stale.txt").exists()
    assert not [p for p in project.root.iterdir() if p.name.startswith(".report")]


def test_cli_report_without_results(tmp_path: Path):
    p = make_project(tmp_path / "proj")
    r = CliRunner().invoke(main, ["report", str(p)])
    assert r.exit_code == 2
    assert "no results: run `radtree simulate" in r.output


def test_facade_coordinates_follow_a_rotated_facade():
    frame = FacadeFrame(azimuth_deg=30.0)
    local = np.array([[u, 0.01, 5.0] for u in (-1.0, 0.0, 2.0)])
    world = frame.to_world(local)
    u, axis = facade_coordinates(world[:, 0], world[:, 1], 30.0)
    np.testing.assert_allclose(u, [-1.0, 0.0, 2.0], atol=0.02)
    np.testing.assert_allclose(axis, frame.along[:2], atol=1e-9)
    u1, _ = facade_coordinates(world[:1, 0], world[:1, 1], 30.0)  # one point: frame axis
    assert u1[0] == pytest.approx(-1.0, abs=0.02)


@needs_radiance
@pytest.mark.radiance
def test_report_on_a_real_open_street_simulation(open_street: Path):
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    data = open_street / "data" / "measured_vertical_illuminance.csv"
    lines = [ln for ln in data.read_text().splitlines()
             if not ln[:2].isdigit() or ln.startswith(("10:30", "13:30"))]
    data.write_text("\n".join(lines) + "\n")
    toml = open_street / "radtree.toml"  # a 3 × 3 dense grid keeps rtrace short
    toml.write_text(re.sub(r"^dense_size_m = .*$", "dense_size_m = 1.0",
                           toml.read_text(), flags=re.M))
    p = load_project(open_street)
    simulate_project(p, options=RunOptions(engine="radiance", scenarios=["A", "B"]))
    index = build_report(p)
    parser = parse(index)
    assert "figures/facade_map.png" in parser.images
    for src in parser.images:
        assert (p.report_dir / src).read_bytes()[:8] == PNG
    stats = pd.read_csv(p.report_dir / "statistics.csv")
    assert list(stats["scenario"]) == ["A", "B"]
    assert np.isfinite(stats["rmse"]).all() and (stats["n_hours"] == 2).all()
    assert math.isfinite(float(stats["mbe"].iloc[0]))


def test_diagnose_section_shows_fitted_strength_and_cv(tmp_path):
    from radtree.report.sections import Section, render_section
    from radtree.report.sections.extras import diagnose_data

    def diagnose_section(folder):
        return render_section(Section("diagnose", diagnose_data(folder)))

    pd.DataFrame([{"step": 1, "effect": "sky_diffuse", "explained_fraction": 0.9,
                   "strength": 14900.0, "rmse_before": 0.198, "rmse_after": 0.064,
                   "cv_rmse_before": 0.198, "cv_rmse_after": 0.075,
                   "strength_text": "diffuse horizontal 14 900 lx"}]).to_csv(
        tmp_path / "steps.csv", index=False)
    html = diagnose_section(tmp_path)
    assert "fitted" in html and "sky_diffuse" in html and "diffuse horizontal 14 900 lx" in html
    assert "<td>0.198 → 0.064</td><td>0.198 → 0.075</td>" in html
    assert '<td class="num">90</td>' in html
    (tmp_path / "steps.csv").unlink()
    assert "<table>" not in diagnose_section(tmp_path)
