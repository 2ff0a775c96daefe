"""radtree sweep: designs, case folders, dask execution (LocalCluster), resume, failures,
sensitivity summary and the report fragment.

The integration tests run a reduced Mendoza copy: open street (``model = "none"``), two hours,
scenario B only (ground-reflected light traced, so the ground reflectance matters), no dense
grid, ``-ab 1 -ad 128`` (NumPy engine: 256 rays) — each case takes well under a second.
Engine: ``auto`` (Radiance when found), except where exact equality is asserted (NumPy).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import tomllib
from click.testing import CliRunner

from radtree.cli.sweep import sweep_command
from radtree.errors import ConfigError
from radtree.pipeline.options import RunOptions
from radtree.report.sections import Section, render_section
from radtree.sweep import (
    SweepOptions,
    full_factorial,
    latin_hypercube,
    make_design,
    parse_param,
    plan_sweep,
    run_sweep,
    sensitivity_table,
    sweep_section_data,
)
from radtree.sweep import scheduler as sweep_scheduler
from radtree.tomlout import dumps

from .conftest import MENDOZA, copy_project

PARAMS = ["street.ground_reflectance=0.1,0.2,0.3", "sensors.height_m=4:6:2"]  # 3 × 2 = 6


@pytest.fixture
def project(tmp_path: Path) -> Path:
    p = copy_project(tmp_path / "proj", hours=["10:30", "13:30"])
    toml = p / "radtree.toml"
    text = re.sub(r'model = "\w+"', 'model = "none"', toml.read_text())
    text = text.replace("[sensors]\n", "[sensors]\ndense_grid = false\n")
    text = re.sub(r"^ad = \d+$", "ab = 1\nad = 128", text, flags=re.M)
    text = re.sub(r"^rays = \d+", "rays = 256", text, flags=re.M)
    toml.write_text(text)
    return p


def sweep(project: Path, *, params=PARAMS, out=None, scenarios=("B",), **run):
    """:func:`run_sweep` with the sweep's parameters and output folder, the run's options."""
    return run_sweep(project, sweep=SweepOptions(params=params, out=out),
                     run=RunOptions(scenarios=scenarios, **run))


# ---------------------------------------------------------------- designs
def test_parse_param_range_and_list():
    p = parse_param("tree.crown.trunk_distance_m=2:6:5")
    assert p.kind == "range" and p.levels() == [2.0, 3.0, 4.0, 5.0, 6.0]
    q = parse_param("tree.louvers.layers=3,4,5")
    assert q.kind == "list" and q.values == (3, 4, 5)
    r = parse_param("light.sky=none,perez")
    assert r.values == ("none", "perez")
    assert parse_param("sensors.dense_grid=true,false").values == (True, False)
    assert parse_param("x.y=0.1:0.3:3").levels() == [0.1, 0.2, 0.3]


@pytest.mark.parametrize("text, message", [
    ("tree.crown.trunk_distance_m", "expected FIELD=VALUES"),
    ("tree.crown.trunk_distance_m=2:6:x", "must be a whole number"),
    ("tree.crown.trunk_distance_m=2:6:0", "must be a whole number"),
    ("tree.crown.trunk_distance_m=2:6:2.5", "must be a whole number"),
    ("tree.crown.trunk_distance_m=6:2:3", "below low"),
    ("tree.crown.trunk_distance_m=2:y:3", "not a number"),
    ("tree.crown.trunk_distance_m=2:4:6:8", "bad range"),
    ("tree.crown.trunk_distance_m=", "no values"),
    ("tree.crown.trunk_distance_m=1,,2", "empty item"),
    ("tree.crown.trunk_distance_m=1,1", "repeat"),
    ("tree..crown=1", "not a dotted field name"),
])
def test_parse_param_errors(text, message):
    with pytest.raises(ConfigError, match=message):
        parse_param(text)


def test_full_factorial_count_and_order():
    d = full_factorial([parse_param("a.x=1:3:3"), parse_param("a.y=p,q"),
                        parse_param("a.z=0.5,1.5")])
    assert len(d) == 3 * 2 * 2
    assert d.cases[0] == {"a.x": 1.0, "a.y": "p", "a.z": 0.5}
    assert d.cases[1] == {"a.x": 1.0, "a.y": "p", "a.z": 1.5}  # last varies fastest
    assert len({tuple(c.values()) for c in d.cases}) == 12
    with pytest.raises(ConfigError, match="needs the number of values"):
        full_factorial([parse_param("a.x=1:3")])


def test_latin_hypercube_stratified_and_seeded():
    params = [parse_param("a.x=2:6:9"), parse_param("a.y=-1:1"), parse_param("a.k=p,q,r")]
    n = 12
    d = latin_hypercube(params, n, seed=7)
    assert len(d) == n
    for name, lo, hi in (("a.x", 2.0, 6.0), ("a.y", -1.0, 1.0)):
        x = np.array([c[name] for c in d.cases])
        strata = np.floor((x - lo) / (hi - lo) * n).astype(int)
        assert sorted(strata) == list(range(n)), name  # one case in each of n strata
    counts = pd.Series([c["a.k"] for c in d.cases]).value_counts()
    assert sorted(counts) == [4, 4, 4]
    assert latin_hypercube(params, n, seed=7).cases == d.cases
    assert latin_hypercube(params, n, seed=8).cases != d.cases
    assert make_design(params, "lhs", None, 7).cases == latin_hypercube(params, 30, 7).cases


def test_integer_fields(project: Path):
    plan = plan_sweep(project, ["tree.louvers.layers=2:6:3", "engine.ad=64:128",
                                "engine.ab=1:3", "office.bays=1:5", "office.depth_m=4:8"],
                      design="lhs", samples=5, scenarios=["B"], scheduler="sequential")
    for name in ("tree.louvers.layers", "engine.ad", "engine.ab", "office.bays"):
        assert all(type(c[name]) is int for c in plan.design.cases), name
    assert sorted(c["tree.louvers.layers"] for c in plan.design.cases) == [2, 3, 4, 5, 6]
    assert all(type(c["office.depth_m"]) is float for c in plan.design.cases)
    full = plan_sweep(project, ["tree.louvers.layers=3:5:3"], scenarios=["B"])
    assert [c["tree.louvers.layers"] for c in full.design.cases] == [3, 4, 5]
    with pytest.raises(ConfigError, match="integer field"):
        plan_sweep(project, ["tree.louvers.layers=3:6:3"])


# ---------------------------------------------------------------- planning
def test_unknown_fields_and_values_are_clear(project: Path):
    with pytest.raises(ConfigError, match=r"cannot sweep tree\.crown\.nope: not a field"):
        plan_sweep(project, ["tree.crown.nope=1,2"])
    with pytest.raises(ConfigError, match=r"cannot sweep nothing\.here: not a field"):
        plan_sweep(project, ["nothing.here=1,2"])
    with pytest.raises(ConfigError, match="it is a table"):
        plan_sweep(project, ["tree.crown=1,2"])
    with pytest.raises(ConfigError, match="no scenario named 'Z'"):
        plan_sweep(project, PARAMS, scenarios=["Z"])
    with pytest.raises(ConfigError, match="no sweep parameters"):
        plan_sweep(project, None)
    with pytest.raises(ConfigError, match="scheduler"):
        plan_sweep(project, PARAMS, scheduler="bogus")


def test_case_files_are_ordinary_projects(project: Path, tmp_path: Path):
    from radtree.config import load_project

    plan = plan_sweep(project, PARAMS, scenarios=["B"], scheduler="sequential")
    assert len(plan.specs) == 6 and len({s.case_hash for s in plan.specs}) == 6
    spec = plan.specs[3]
    data = tomllib.loads(spec.toml_text)
    assert data["street"]["ground_reflectance"] == spec.params["street.ground_reflectance"]
    assert Path(data["light"]["direct_normal"]).is_absolute()
    assert Path(data["project"]["measured"]).is_absolute()
    assert "sweep" not in data
    # loads from anywhere (the data paths are absolute)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "radtree.toml").write_text(spec.toml_text)
    p = load_project(elsewhere)
    assert p.sensors.height_m == spec.params["sensors.height_m"]
    # the same sweep planned again gives the same hashes (hash keyed by parameters)
    again = plan_sweep(project, PARAMS, scenarios=["B"], scheduler="sequential")
    assert [s.case_hash for s in again.specs] == [s.case_hash for s in plan.specs]


def test_toml_writer_round_trips_the_example():
    data = tomllib.loads((MENDOZA / "radtree.toml").read_text())
    data["x"] = {"s": 'quote " and \\ back', "f": 1e-7, "i": -3, "b": False, "l": [1, 2.5, "a"],
                 "t": {"k.dot": 1}}
    assert tomllib.loads(dumps(data, header="a\nb")) == data


def test_sweep_table_in_project_file(project: Path):
    toml = project / "radtree.toml"
    toml.write_text(toml.read_text() + '\n[sweep]\ndesign = "lhs"\nsamples = 4\nseed = 3\n'
                    'scenarios = ["B"]\n\n[sweep.params]\n"sensors.height_m" = "4:6"\n'
                    'street.ground_reflectance = [0.1, 0.3]\n\n[sweep.set]\n'
                    '"engine.ad" = 64\n')
    plan = plan_sweep(project)
    assert plan.design.kind == "lhs" and len(plan.specs) == 4 and plan.design.seed == 3
    assert plan.design.names == ["sensors.height_m", "street.ground_reflectance"]
    assert all(tomllib.loads(s.toml_text)["engine"]["ad"] == 64 for s in plan.specs)
    # command-line values win over the table
    plan2 = plan_sweep(project, ["sensors.height_m=4,5"], design="full")
    assert plan2.design.kind == "full" and len(plan2.specs) == 2
    toml.write_text(toml.read_text().replace("samples = 4", "samples = 0"))
    with pytest.raises(ConfigError, match="sweep.samples"):
        plan_sweep(project)


# ---------------------------------------------------------------- running
def test_local_cluster_matches_sequential(project: Path, tmp_path: Path):
    # NumPy engine: seeded, so the two runs must agree to the last digit. (Radiance 6's rtrace
    # samples with -u+ by default, seeded from the clock, so two runs differ by ~1 %.)
    par = sweep(project, scheduler="local", workers=2, out=tmp_path / "cluster", engine="numpy")
    seq = sweep(project, scheduler="sequential", engine="numpy")  # out: PROJECT/sweep
    assert len(par.computed) == len(seq.computed) == 6 and not par.failed
    cases = pd.read_csv(tmp_path / "cluster" / "cases.csv")
    assert os.getpid() not in set(cases["pid"])  # ran in worker processes
    assert set(pd.read_csv(project / "sweep" / "cases.csv")["pid"]) == {os.getpid()}
    a = pd.read_csv(tmp_path / "cluster" / "results.csv")
    b = pd.read_csv(project / "sweep" / "results.csv")
    pd.testing.assert_frame_equal(a, b)
    assert list(a.columns[:4]) == ["case_id", "case_hash", "street.ground_reflectance",
                                   "sensors.height_m"]
    assert a["case_id"].nunique() == 6 and set(a["scenario"]) == {"B"}
    assert set(a["time"]) == {"10:30", "13:30"}
    # the traced ground reflectance moves the façade lux; the summary says so
    sens = pd.read_csv(project / "sweep" / "sensitivity.csv")
    lux = sens[sens["metric"] == "facade_mean_lux"].set_index("parameter")
    assert lux.loc["street.ground_reflectance", "effect_range"] > 0
    assert lux.loc["street.ground_reflectance", "value_at_high"] == 0.3
    assert {"nrmse", "nmbe"} <= set(sens["metric"])
    assert (project / "sweep" / "tornado.png").stat().st_size > 1000
    html = render_section(Section("sweep", sweep_section_data(project)))
    assert "<section" in html and "scenario B" in html
    assert "Scenario A was not in the sweep" in html
    assert "data:image/png;base64," in html


def test_resume_on_existing_cluster_recomputes_only_missing(project: Path):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        first = sweep(project, scheduler=cluster.scheduler_address)
        assert len(first.computed) == 6
        results = {s: project / "sweep" / "cases" / h / "result.csv"
                   for s, h in zip(first.cases["case_id"], first.cases["case_hash"])}
        stamps = {c: f.stat().st_mtime_ns for c, f in results.items()}
        results["c004"].unlink()
        # a half-written result of an interrupted case does not count as finished
        (results["c004"].parent / ".result.csv.abcd.tmp").write_text("time,lux\n10:30,")
        second = sweep(project, scheduler=cluster.scheduler_address)
    assert second.computed == ["c004"] and len(second.reused) == 5
    for c, f in results.items():
        if c != "c004":
            assert f.stat().st_mtime_ns == stamps[c]
    pd.testing.assert_frame_equal(first.table, second.table)
    status = pd.read_csv(project / "sweep" / "cases.csv").set_index("case_id")["status"]
    assert status["c004"] == "done" and (status.drop("c004") == "reused").all()


def test_interrupted_sweep_resumes(project: Path, monkeypatch):
    real = sweep_scheduler.run_case
    calls: list[str] = []

    def flaky(spec):
        if len(calls) == 2:
            raise KeyboardInterrupt
        calls.append(spec.case_id)
        return real(spec)

    monkeypatch.setattr(sweep_scheduler, "run_case", flaky)
    with pytest.raises(KeyboardInterrupt):
        sweep(project, scheduler="sequential")
    monkeypatch.setattr(sweep_scheduler, "run_case", real)
    out = sweep(project, scheduler="sequential")
    assert out.reused == calls == ["c001", "c002"]
    assert out.computed == ["c003", "c004", "c005", "c006"]


def test_invalid_case_fails_alone(project: Path):
    out = sweep(project, params=["sensors.height_m=-1,5", "street.ground_reflectance=0.1,0.2"],
                scheduler="sequential")
    assert out.failed == ["c001", "c002"] and out.computed == ["c003", "c004"]
    fails = pd.read_csv(project / "sweep" / "failures.csv")
    assert list(fails["sensors.height_m"]) == [-1, -1]
    assert list(fails["street.ground_reflectance"]) == [0.1, 0.2]
    assert fails["error"].str.contains(r"field 'sensors.height_m': got -1.0, expected > 0").all()
    assert set(out.table["case_id"]) == {"c003", "c004"}
    # each case's messages go to its own case.log, in whichever process ran it
    h = out.cases.set_index("case_id").loc["c003", "case_hash"]
    log_text = (project / "sweep" / "cases" / h / "case.log").read_text()
    assert log_text.startswith(f"--- case {h} on ") and f"pid {os.getpid()} at " in log_text
    # failed cases are retried on a rerun (and fail again), finished ones are not
    again = sweep(project, params=["sensors.height_m=-1,5", "street.ground_reflectance=0.1,0.2"],
                  scheduler="sequential")
    assert again.failed == ["c001", "c002"] and again.reused == ["c003", "c004"]


def test_cli(project: Path):
    runner = CliRunner()
    res = runner.invoke(sweep_command, [str(project), "-p", "sensors.height_m=4,6", "-s", "B",
                                        "--scheduler", "sequential", "--no-progress",
                                        "--set", "engine.ad=64"])
    assert res.exit_code == 0, res.output
    assert "2 cases run, 0 reused, 0 failed" in res.output
    assert "scenario B: nRMSE range by parameter" in res.output
    assert (project / "sweep" / "results.csv").exists()
    bad = runner.invoke(sweep_command, [str(project), "-p", "sensors.height_m=4:6:x"])
    assert isinstance(bad.exception, ConfigError) and "whole number" in str(bad.exception)
    # registered in the radtree group, errors become one clear line and exit code 2
    from radtree.cli.errors import RadtreeGroup

    group = RadtreeGroup(commands={"sweep": sweep_command})
    res = runner.invoke(group, ["sweep", str(project), "-p", "tree.crown.nope=1,2"])
    assert res.exit_code == 2
    assert "error:" in res.output and "cannot sweep tree.crown.nope: not a field" in res.output


# ---------------------------------------------------------------- sensitivity
def test_sensitivity_main_effects_and_spearman():
    rng = np.random.default_rng(0)
    a, b = np.meshgrid([1.0, 2.0, 3.0], [10.0, 20.0], indexing="ij")
    m = pd.DataFrame({"p.a": a.ravel(), "p.b": b.ravel(), "scenario": "A"})
    m["facade_mean_lux"] = 100 * m["p.a"] + 1 * m["p.b"]
    m["nrmse"] = 0.1 * m["p.a"]
    s = sensitivity_table(m, ["p.a", "p.b"], "full").set_index(["parameter", "metric"])
    assert s.loc[("p.a", "facade_mean_lux"), "effect_range"] == pytest.approx(200)
    assert s.loc[("p.b", "facade_mean_lux"), "effect_range"] == pytest.approx(10)
    assert s.loc[("p.a", "nrmse"), "value_at_high"] == 3.0
    assert s.loc[("p.a", "nrmse"), "spearman_rho"] == pytest.approx(1.0)
    assert s.loc[("p.b", "nrmse"), "spearman_rho"] == pytest.approx(0.0)  # nrmse ignores b
    assert s.loc[("p.b", "nrmse"), "effect_range"] == pytest.approx(0.0)
    # Latin hypercube: binned main effects and rank correlation
    x = rng.permutation(40) / 40
    lhs = pd.DataFrame({"p.x": x, "scenario": "A", "facade_mean_lux": -5 * x + 1,
                        "nrmse": x**2})
    t = sensitivity_table(lhs, ["p.x"], "lhs").set_index("metric")
    assert t.loc["nrmse", "spearman_rho"] == pytest.approx(1.0)
    assert t.loc["facade_mean_lux", "spearman_rho"] == pytest.approx(-1.0)
    assert t.loc["nrmse", "levels"] == 5 and "binned" in t.loc["nrmse", "method"]


def test_report_section_empty_without_sweep(project: Path):
    assert sweep_section_data(project) is None
