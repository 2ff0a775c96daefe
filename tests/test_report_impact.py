"""The report answers what the trees do (issue 38), on the shipped examples traced small with the
NumPy engine: the first table is the tree-impact table where a with/without pair exists and its
numbers are the results table's; sections without data are absent; the light is described from
the manifest's weather record; no reference-study sentence outside the reference example;
index.md has the sections index.html has; every path printed exists afterwards; and a headless
Chromium renders the district report without a console error with the impact table above the
fold."""

from __future__ import annotations

import io
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from radtree import log
from radtree.config import load_project
from radtree.pipeline.options import RunOptions
from radtree.pipeline.simulate import simulate_project
from radtree.report import build_report
from radtree.report.impact import Pair, impact_frame, tree_pairs

from .conftest import ROOT
from .test_report import body, built, parse, table  # noqa: F401  (the reference report)

#: sentences only the reference study's report may hold (lower case)
REFERENCE_WORDS = ("mulberry", "morus", "the study", "stand-in", "sensor rows", "mendoza")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _example(tmp: Path, name: str, edits: dict[str, str]) -> Path:
    dst = tmp / name
    shutil.copytree(ROOT / "examples" / name, dst,
                    ignore=shutil.ignore_patterns("build", "results", "report"))
    if name == "honeybee-office":   # it reads the office block's light files
        shutil.copytree(ROOT / "examples" / "office-block" / "data", tmp / "office-block" / "data")
    toml = dst / "radtree.toml"
    text = toml.read_text()
    for pat, rep in edits.items():
        text, n = re.subn(pat, rep, text, flags=re.M)
        assert n, pat
    toml.write_text(text)
    return dst


def _traced(folder: Path) -> tuple[object, Path, list[str]]:
    project = load_project(folder)
    simulate_project(project, options=RunOptions(engine="numpy"))
    printed: list[str] = []
    stream = io.StringIO()
    log.enable(stream=stream, progress=False)    # the messages the CLI would print
    try:
        index = build_report(project)
    finally:
        log.disable()
    printed += stream.getvalue().splitlines()
    assert printed[0] == f"report for {project.name}"
    return project, index, printed


@pytest.fixture(scope="module")
def district(tmp_path_factory):
    return _traced(_example(tmp_path_factory.mktemp("d"), "district", {
        r"^hours = .*$": 'hours = ["10:30", "13:30"]', r"^rays = \d+": "rays = 32"}))


@pytest.fixture(scope="module")
def office(tmp_path_factory):
    return _traced(_example(tmp_path_factory.mktemp("o"), "office-block", {
        r"^rays = \d+": "rays = 16", r"^ad = \d+": "ad = 32",
        r"^workers = \d+": "workers = 1"}))


@pytest.fixture(scope="module")
def honeybee(tmp_path_factory):
    return _traced(_example(tmp_path_factory.mktemp("h"), "honeybee-office", {
        r"^hours = .*$": 'hours = ["13:30"]', r"^ad = \d+": "ad = 64"}))


def _reference_free(project, index: Path) -> None:
    """No reference-study sentence: only the project's own names may say Mendoza."""
    for path in (index, index.with_suffix(".md")):
        text = path.read_text(encoding="utf-8")
        for own in (project.site.name, project.name):
            text = text.replace(own, "")
        low = text.lower()
        found = [w for w in REFERENCE_WORDS if w in low]
        assert not found, (path.name, found)


def _same_sections(index: Path) -> list[str]:
    html = re.findall(r"<h2[^>]*>([^<]+)</h2>", index.read_text(encoding="utf-8"))
    md = re.findall(r"^## (.+)$", index.with_suffix(".md").read_text(encoding="utf-8"), re.M)
    assert [h.strip() for h in html] == [h.strip() for h in md]
    return md


def _printed_paths_exist(printed: list[str]) -> None:
    for line in printed:
        for p in re.findall(r"(/\S+)", line):
            assert Path(p.rstrip(".,)")).exists(), line


def _light_matches_manifest(project, index: Path, scenario: str) -> None:
    records = json.loads((project.results_dir / "manifest.json").read_text())["weather"]
    rows = body(table(parse(index), "light"))
    rec = records[scenario]
    mine = [r for r in rows if scenario in r[0][2].split(", ")]
    assert [r[1][2] for r in mine] == [x["time"] for x in rec]
    for r, x in zip(mine, rec):
        assert float(r[2][2].replace(",", "")) == pytest.approx(x["direct_normal_lux"], abs=0.5)
        assert float(r[3][2].replace(",", "")) == pytest.approx(x["diffuse_horizontal_lux"],
                                                                abs=0.5)
        if len(r) > 5:   # several sources: a column; one: named once in the caption
            assert r[5][2] == x["source"]
        else:
            assert f"every hour's source: {x['source']}" in index.with_suffix(".md").read_text(
                encoding="utf-8")
    # the DNI is the project's table, the diffuse its stated constant: no default string
    dni = pd.read_csv(project.light.direct_normal_table, comment="#").set_index("time")
    for x in rec:
        assert x["direct_normal_lux"] == pytest.approx(dni.loc[x["time"], "direct_normal_lux"])
        assert x["diffuse_horizontal_lux"] == project.light.diffuse_horizontal_lux


def test_district_report_opens_with_the_change_per_facade(district):
    project, index, printed = district
    parser = parse(index)
    assert parser.tables[0]["id"] == "t-impact_facades"
    results = pd.read_csv(project.results_dir / "illuminance.csv", dtype={"facade": str})
    fac = results[results["facade"].notna()]
    day = fac.groupby(["scenario", "facade", "time"])["lux"].mean().groupby(
        ["scenario", "facade"]).mean()
    rows = body(parser.tables[0])
    assert len(rows) == fac["facade"].nunique()
    for r in rows:
        f = r[0][2]
        w, o = day[("trees", f)], day[("bare", f)]
        assert float(r[2][2]) == pytest.approx(w, abs=0.5)
        assert float(r[3][2]) == pytest.approx(o, abs=0.5)
        assert float(r[4][2].split("±")[0]) == pytest.approx(w - o, abs=1)
        assert float(r[5][2]) == pytest.approx(100 * (w - o) / o, abs=0.05)
    pcts = [float(r[5][2]) for r in rows]
    assert pcts == sorted(pcts) and pcts[0] < -10       # most light taken first
    assert body(table(parser, "impact_storeys"))
    html = index.read_text()
    for absent in ("statistics", "rows", "maps", "convergence"):
        assert f'<section id="{absent}"' not in html, absent
    assert "(compass)" not in html and "dense_grid = true" not in html
    assert html.index('id="provenance"') > html.index('id="appendix"') > html.index(
        'id="facades"')
    fc = json.loads((project.results_dir / "facades.geojson").read_text())
    props = {f["properties"]["facade"]: f["properties"] for f in fc["features"]}
    some = rows[0][0][2]
    assert props[some]["change_pct"] == pytest.approx(float(rows[0][5][2]), abs=0.05)
    assert "change_pct_13:30" in props[some] and props[some]["baseline"] == "bare"
    _light_matches_manifest(project, index, "trees")
    _reference_free(project, index)
    assert _same_sections(index)[0] == "What the trees do"
    _printed_paths_exist(printed)


def test_office_report_rooms(office):
    project, index, printed = office
    parser = parse(index)
    assert parser.tables[0]["id"] == "t-impact_facades"
    rooms = body(table(parser, "impact_rooms"))
    assert [r[0][2] for r in rooms] == ["workplane"]
    res = pd.read_csv(project.results_dir / "illuminance.csv")
    wp = res[res["grid"] == "workplane"].groupby("scenario")["lux"].mean()
    assert float(rooms[0][2][2]) == pytest.approx(wp["with"], abs=0.5)
    assert float(rooms[0][3][2]) == pytest.approx(wp["without"], abs=0.5)
    csv = pd.read_csv(project.results_dir / "rooms.csv")
    day = csv[(csv["room"] == "workplane") & (csv["time"] == "day")].iloc[0]
    assert day["with"] == pytest.approx(wp["with"], abs=0.06)
    assert day["change_pct"] == pytest.approx(100 * (wp["with"] - wp["without"])
                                              / wp["without"], abs=0.01)
    html = index.read_text()
    assert '<section id="statistics"' in html          # the office has measurements
    assert '<section id="rows"' not in html            # not the reference study
    assert "Office block: the sensed offices" in _same_sections(index)   # md has it too
    _light_matches_manifest(project, index, "with")
    _reference_free(project, index)
    _printed_paths_exist(printed)


def test_honeybee_report_rooms(honeybee):
    project, index, printed = honeybee
    parser = parse(index)
    assert parser.tables[0]["id"] in ("t-impact_facades", "t-impact_rooms")
    pairs = tree_pairs(project, ["model", "crown"])
    assert pairs == [Pair("crown", "model")]
    rooms = pd.read_csv(project.results_dir / "rooms.csv")
    assert set(rooms["room"]) and (rooms["trees"] == "crown").all()
    md = _same_sections(index)
    assert "Honeybee model" in md
    _reference_free(project, index)
    _printed_paths_exist(printed)


def test_reference_report_keeps_its_study_sections(built):  # noqa: F811
    project, index = built
    html = index.read_text()
    assert 'id="t-impact_facades"' not in html          # no with/without-trees pair
    for present in ("statistics", "rows"):
        assert f'<section id="{present}"' in html
    _same_sections(index)


def test_baseline_marks_the_pair_and_leaves_hashes(tmp_path):
    folder = _example(tmp_path, "office-block", {r'^name = "without"$':
                                                 'name = "without"\nbaseline = true'})
    p = load_project(folder)
    q = load_project(ROOT / "examples" / "office-block")
    assert [s.baseline for s in p.scenarios] == [False, True]
    assert p.params_hash(p.scenarios[1]) == q.params_hash(q.scenarios[1])
    assert tree_pairs(p, ["with", "without"]) == [Pair("with", "without")]
    text = (folder / "radtree.toml").read_text().replace('name = "with"\n',
                                                          'name = "with"\nbaseline = true\n')
    (folder / "radtree.toml").write_text(text)
    from radtree.errors import ConfigError

    with pytest.raises(ConfigError, match=r"field 'scenario.baseline'.*with, without: mark one"):
        load_project(folder)


def test_impact_of_a_known_table():
    """Two scenarios, two façade sensors and a room, two hours: the numbers by hand."""
    rows = []
    for scen, f in (("trees", 0.5), ("open", 1.0)):
        for t, base in (("10:00", 1000.0), ("12:00", 2000.0)):
            for grid, s, lux in (("facade", 0, base), ("facade", 1, 3 * base),
                                 ("room1", 0, base / 10)):
                rows.append({"scenario": scen, "time": t, "grid": grid, "sensor": s,
                             "lux": lux * (f if grid == "facade" else 1.0),
                             "lux_stderr": 3.0})
    out = impact_frame(pd.DataFrame(rows), [Pair("trees", "open")])
    f = out[(out["level"] == "façade") & (out["time"] == "10:00")].iloc[0]
    assert (f["with_lux"], f["without_lux"], f["change_lux"], f["change_pct"]) == (
        1000.0, 2000.0, -1000.0, -50.0)
    assert f["change_stderr"] == pytest.approx(np.hypot(3 * np.sqrt(2) / 2, 3 * np.sqrt(2) / 2))
    d = out[(out["level"] == "façade") & (out["time"] == "day")].iloc[0]
    assert d["with_lux"] == 1500.0 and d["change_pct"] == -50.0
    r = out[(out["level"] == "room") & (out["time"] == "day")].iloc[0]
    assert r["target"] == "room1" and r["change_lux"] == 0.0


@pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (.ci/run installs it)")
def test_district_report_in_headless_chromium(district, tmp_path):
    """No console error, and the tree-impact table's top edge inside the first screen."""
    _, index, _ = district
    probe = index.parent / "probe.html"
    probe.write_text(index.read_text().replace("</body>", (
        "<script>window.addEventListener('load', function () {"
        "var t = document.getElementById('t-impact_facades').getBoundingClientRect();"
        "document.body.setAttribute('data-table-top', Math.round(t.top));});</script></body>")))
    try:
        run = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
                              "--no-first-run", "--disable-extensions", "--window-size=1280,900",
                              "--enable-logging=stderr", "--v=0",
                              "--virtual-time-budget=3000", "--dump-dom", probe.as_uri()],
                             capture_output=True, text=True, timeout=120, check=True)
        shot = tmp_path / "report.png"
        subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
                        "--no-first-run", "--disable-extensions", "--window-size=1280,900",
                        "--hide-scrollbars", "--virtual-time-budget=3000",
                        f"--screenshot={shot}", index.as_uri()],
                       capture_output=True, timeout=120, check=True)
    finally:
        probe.unlink()
    top = int(re.search(r'data-table-top="(-?\d+)"', run.stdout).group(1))
    assert 0 < top < 900 - 150, top          # the table starts in the first screen
    # Chromium logs every console message (log, error, uncaught exception) as INFO:CONSOLE;
    # its own notes on software WebGL (a 3-D view on a machine without GPU) are not the page's
    console = [ln for ln in run.stderr.splitlines() if ("CONSOLE" in ln or "Uncaught" in ln)
               and "software WebGL" not in ln and "GL Driver Message" not in ln]
    assert not console, console
    from PIL import Image

    assert Image.open(shot).size == (1280, 900)


def test_trees_ranked_and_standards_from_the_contract_files(district):
    """results/tree_impact.csv and results/annual/standards.csv (written by the attribution
    and the annual standards): the trees ranked by light removed, the standards with the
    difference with − without."""
    project, _, _ = district
    trees = [t for t in json.loads((project.root / "data" / "trees.geojson").read_text())[
        "features"]][:3]
    ids = [str(t.get("id", t["properties"].get("id"))) for t in trees]
    rows = []
    for k, (tid, lux) in enumerate(zip(ids, (50.0, 400.0, 120.0))):
        for time in ("10:30", "13:30"):
            rows.append({"scenario": "trees", "time": time, "tree": tid, "target": "B05:3",
                         "grid": "g", "lux_removed": lux, "lux_removed_stderr": 3.0,
                         "share": 0.1 * (k + 1)})
    pd.DataFrame(rows).to_csv(project.results_dir / "tree_impact.csv", index=False)
    (project.results_dir / "annual").mkdir(exist_ok=True)
    pd.DataFrame([
        {"scenario": "trees", "target": "B05:3", "metric": "sDA300_50", "value": 40.0,
         "unit": "%", "definition": "share of the area with DA300 ≥ 50 %"},
        {"scenario": "bare", "target": "B05:3", "metric": "sDA300_50", "value": 55.0,
         "unit": "%", "definition": "share of the area with DA300 ≥ 50 %"},
    ]).to_csv(project.results_dir / "annual" / "standards.csv", index=False)
    try:
        parser = parse(build_report(project))
    finally:
        (project.results_dir / "tree_impact.csv").unlink()
        shutil.rmtree(project.results_dir / "annual")
    ranked = body(table(parser, "tree_ranking"))
    assert [r[1][2] for r in ranked] == [ids[1], ids[2], ids[0]]
    assert [r[2][2] for r in ranked] == ["800 ± 4", "240 ± 4", "100 ± 4"]
    assert ranked[0][5][2] == "20"
    std = body(table(parser, "impact_standards"))
    assert [c[2] for c in std[0][:6]] == ["B05:3", "sDA300_50", "40.0", "55.0", "-15.0", "%"]


def test_annual_metrics_with_without_and_rooms_csv(tmp_path):
    """annual.csv / annual_summary.csv (radtree annual's layout) → with, without, difference
    per grid, and the rows rooms.csv carries for them."""
    from types import SimpleNamespace

    from radtree.report.sections.impact import annual_rows, rooms_frame

    res = tmp_path / "results"
    res.mkdir()
    pd.DataFrame({"grid": ["office"] * 4, "sensor": [0, 1, 0, 1],
                  "tree": ["with", "with", "without", "without"],
                  "udi_below_100": [10.0, 20.0, 5.0, 5.0], "udi_100_300": [0.0] * 4,
                  "udi_300_3000": [90.0, 80.0, 95.0, 95.0], "udi_above_3000": [0.0] * 4,
                  "da_300": [60.0, 40.0, 80.0, 70.0], "ase_hours": [0.0, 10.0, 100.0, 300.0]}
                 ).to_csv(res / "annual.csv", index=False)
    pd.DataFrame({"grid": ["office"] * 2, "tree": ["with", "without"], "sda_300_50": [50.0, 100.0],
                  "ase_1000_250": [0.0, 50.0], "month": [1, 1], "mean_lux": [1.0, 2.0]}
                 ).to_csv(res / "annual_summary.csv", index=False)
    rows = annual_rows(SimpleNamespace(results_dir=res)).set_index("metric")
    assert (rows.loc["sDA300/50%", "with"], rows.loc["sDA300/50%", "without"],
            rows.loc["sDA300/50%", "difference"]) == (50.0, 100.0, -50.0)
    assert rows.loc["DA300", "with"] == 50.0 and rows.loc["DA300", "without"] == 75.0
    assert rows.loc["direct-sun hours > 1000 lx", "difference"] == -195.0
    impact = impact_frame(pd.DataFrame({
        "scenario": ["t", "o"], "time": ["12:00"] * 2, "grid": ["office"] * 2, "sensor": [0, 0],
        "lux": [300.0, 400.0], "lux_stderr": [np.nan] * 2}), [Pair("t", "o")])
    csv = rooms_frame(impact, rows.reset_index(), None, Pair("t", "o"))
    day = csv[(csv["time"] == "day")].iloc[0]
    assert (day["with"], day["without"], day["change"], day["change_pct"]) == (
        300.0, 400.0, -100.0, -25.0)
    sda = csv[csv["quantity"] == "sDA300/50%"].iloc[0]
    assert (sda["time"], sda["change"], sda["change_pct"], sda["trees"]) == (
        "annual", -50.0, -50.0, "t")


def test_stand_in_scenario_is_marked_and_off_the_scale(tmp_path, monkeypatch):
    """A photo scenario from the stand-in photo (F-photo): marked in the scenario table, dotted
    and not setting the headline figure's vertical scale."""
    from radtree.report.data import collect
    from radtree.report.figures import hourly_plot

    from .conftest import copy_project
    from .test_report import write_results

    folder = copy_project(tmp_path / "proj", photo=True)
    p = load_project(folder)
    write_results(p)
    table_ = pd.read_csv(p.results_dir / "illuminance.csv", dtype={"scenario": str})
    fphoto = table_[table_["scenario"] == "F"].assign(
        scenario="F-photo", params_hash=p.params_hash(p.scenario("F-photo")))
    fphoto["lux"] *= 6.0
    pd.concat([table_, fphoto]).to_csv(p.results_dir / "illuminance.csv", index=False)
    data = collect(p)
    assert [s.name for s in data.scenarios if s.stand_in] == ["F-photo"]
    from matplotlib.figure import Figure

    seen = {}
    original = Figure.savefig

    def spy(fig, *a, **k):
        seen["ylim"] = fig.axes[0].get_ylim()
        return original(fig, *a, **k)

    monkeypatch.setattr(Figure, "savefig", spy)
    caption = hourly_plot(data, tmp_path / "h.png")
    top = max(data.hourly_sim[data.hourly_sim["scenario"] != "F-photo"]["lux"].max(),
              data.measured["measured_lux"].max())
    assert "stand-in scenario(s) F-photo" in caption
    assert seen["ylim"][1] < 1.2 * top < data.hourly_sim["lux"].max()


def test_change_stderr_unknown_when_the_engine_gives_none():
    """Radiance estimates no standard error: the change's is unknown (NaN, printed without
    ±), not 0; with the NumPy engine's per-sensor errors it is the root sum of squares."""
    from radtree.report.impact import Pair, impact_frame

    def rows(scenario: str, lux: list[float], se: list[float]) -> pd.DataFrame:
        return pd.DataFrame({"scenario": scenario, "time": "12:00", "grid": "facade",
                             "sensor": range(len(lux)), "lux": lux, "lux_stderr": se})

    nan = float("nan")
    radiance = impact_frame(pd.concat([rows("trees", [100.0, 300.0], [nan, nan]),
                                       rows("open", [400.0, 600.0], [nan, nan])]),
                            [Pair("trees", "open")])
    assert radiance["change_lux"].tolist() == [-300.0, -300.0]     # the hour and the day
    assert radiance["change_stderr"].isna().all()
    numpy = impact_frame(pd.concat([rows("trees", [100.0, 300.0], [3.0, 4.0]),
                                    rows("open", [400.0, 600.0], [0.0, 0.0])]),
                         [Pair("trees", "open")])
    assert numpy["change_stderr"].tolist() == pytest.approx([2.5, 2.5])


@pytest.mark.parametrize(("zone", "date", "hours"), [
    ("Europe/Paris", "2024-06-21", 2.0), ("Europe/Paris", "2024-12-21", 1.0),
    ("Australia/Sydney", "2024-12-21", 11.0), ("Australia/Sydney", "2024-06-21", 10.0),
    ("Asia/Kolkata", "2024-06-21", 5.5), ("UTC-3", "2024-06-21", -3.0)])
def test_hourly_figure_names_the_civil_offset_of_the_date(zone, date, hours):
    """The hourly figure's time axis says the clock the hours are in: daylight saving
    included (Paris in June is UTC+2, not its standard UTC+1)."""
    from radtree.config.timezone import parse_time_zone
    from radtree.report.figures import clock_offset_hours

    site = type("S", (), {"date": date, "time_zone": zone, "utc_offset_hours": -99.0,
                          "tzinfo": parse_time_zone(zone)})()
    assert clock_offset_hours(site) == hours
