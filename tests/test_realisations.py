"""Crown realisations: a volume-louvers scenario traced with several random crowns and averaged
back into one scenario (real NumPy traces of a reduced Mendoza example; Radiance build folders)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.pipeline.build import build_project
from radtree.pipeline.options import RunOptions
from radtree.pipeline.realisations import merge_realisations, selected
from radtree.pipeline.simulate import simulate_project

from .conftest import copy_project, needs_radiance


@pytest.fixture
def reduced(tmp_path):
    p = copy_project(tmp_path / "proj", hours=["13:30"],
                     replace={r'"louvers.realisations" = 8': '"louvers.realisations" = 3',
                              r"^rays = \d+": "rays = 96",
                              r"^dense_spacing_m = .*$": "dense_spacing_m = 2.0"})
    return p


def test_selected_expands_and_picks(reduced):
    proj = load_project(reduced)
    names = [s.name for s in selected(proj, None)]
    assert names[-3:] == ["F@1", "F@2", "F@3"] and "F" not in names and "A" in names
    subs = selected(proj, ["F"])
    assert [s.switches["louvers.seed"] for s in subs] == [1, 2, 3]
    assert all(s.switches["louvers.realisations"] == 1 for s in subs)
    assert [s.name for s in selected(proj, ["F@2"])] == ["F@2"]
    for bad in ("F@4", "F@x", "A@1"):
        with pytest.raises(ConfigError, match="realisation"):
            selected(proj, [bad])


def test_merge_realisations_by_hand():
    rows = []
    for k, lux in ((1, [100.0, 200.0]), (2, [110.0, 230.0]), (3, [90.0, 170.0])):
        for s, v in enumerate(lux):
            rows.append({"scenario": f"F@{k}", "time": "13:30", "grid": "facade", "sensor": s,
                         "lux": v, "lux_traced": v - 10, "lux_stderr": 1.0,
                         "params_hash": f"h{k}"})
    rows.append({"scenario": "F@1", "time": "13:30", "grid": "facade_map", "sensor": 0,
                 "lux": 55.0, "lux_traced": 55.0, "lux_stderr": 2.0, "params_hash": "h1"})
    rows.append({"scenario": "A", "time": "13:30", "grid": "facade", "sensor": 0,
                 "lux": 7.0, "lux_traced": 7.0, "lux_stderr": 0.5, "params_hash": "a"})
    merged, per = merge_realisations(pd.DataFrame(rows), {"F": "hF"})
    f = merged[(merged.scenario == "F") & (merged.grid == "facade")].sort_values("sensor")
    np.testing.assert_allclose(f["lux"], [100.0, 200.0])
    np.testing.assert_allclose(f["lux_traced"], [90.0, 190.0])
    np.testing.assert_allclose(f["lux_realisation_sd"], [10.0, 30.0])
    np.testing.assert_allclose(f["lux_stderr"], [10.0 / np.sqrt(3), 30.0 / np.sqrt(3)])
    assert set(f["realisations"]) == {3} and set(merged.loc[merged.scenario == "F",
                                                             "params_hash"]) == {"hF"}
    m = merged[merged.grid == "facade_map"].iloc[0]
    assert m["lux"] == 55.0 and m["lux_stderr"] == 2.0 and m["realisations"] == 1
    assert merged[merged.scenario == "A"]["lux"].tolist() == [7.0]
    assert len(per) == 7 and sorted(per["realisation"].unique()) == [1, 2, 3]


def test_simulate_averages_realisations(reduced):
    proj = load_project(reduced)
    out = simulate_project(proj, options=RunOptions(engine="numpy", scenarios=["F"], workers=2))
    df = out.table
    assert set(df["scenario"]) == {"F"}
    fac = df[df.grid == "facade"].sort_values("sensor")
    per = pd.read_csv(proj.results_dir / "realisations.csv")
    per = per[per.grid == "facade"]
    assert sorted(per["realisation"].unique()) == [1, 2, 3]
    wide = per.pivot_table(index="sensor", columns="realisation", values="lux")
    np.testing.assert_allclose(fac["lux"].to_numpy(), wide.mean(axis=1).to_numpy(), rtol=1e-9)
    np.testing.assert_allclose(fac["lux_stderr"].to_numpy(),
                               wide.std(axis=1, ddof=1).to_numpy() / np.sqrt(3), rtol=1e-9)
    # three different crowns: the realisations differ
    assert wide.std(axis=1).min() > 0
    # the dense map is traced in the first realisation only
    assert set(per[per.grid == "facade_map"]["realisation"]) <= {1}
    assert (df[df.grid == "facade_map"]["realisations"] == 1).all()
    timing = pd.read_csv(proj.results_dir / "timing.csv")
    assert timing["scenario"].tolist() == ["F"]
    # the report lists each crown alone: nRMSE of one hour = |measured − simulated| / measured
    from radtree.report.sections import Section, render_section
    from radtree.report.sections.extras import realisation_frame, realisations_data

    crowns = realisation_frame(proj)
    assert crowns["realisation"].tolist() == [1, 2, 3]
    np.testing.assert_allclose(crowns["13:30"], wide.mean(axis=0).to_numpy(), rtol=1e-9)
    np.testing.assert_allclose(crowns["nrmse"], np.abs(1592.0 - crowns["13:30"]) / 1592.0)
    html = render_section(Section("realisations", realisations_data(proj)))
    assert html.count("<tr><td>F</td>") == 3 and "single crowns give nRMSE" in html
    md = render_section(Section("realisations", realisations_data(proj)), html=False)
    assert "## Crown realisations" in md and md.count("\n| F | ") == 3


@needs_radiance
def test_build_writes_one_folder_per_realisation(reduced):
    proj = load_project(reduced)
    facts = build_project(proj, ["F"], pictures=False)
    assert sorted(facts) == ["F@1", "F@2", "F@3"]
    for k in (1, 2, 3):
        assert (proj.build_dir / f"F@{k}" / "Makefile").exists()
    assert "SCENARIOS := F@1 F@2 F@3" in (proj.build_dir / "Makefile").read_text()
    # different random crowns, same hours
    g1 = (proj.build_dir / "F@1" / "geometry" / "tree_leaves.rad").read_text()
    g2 = (proj.build_dir / "F@2" / "geometry" / "tree_leaves.rad").read_text()
    assert g1 != g2
    assert "facade_map" not in (proj.build_dir / "F@2" / "Makefile").read_text().split(
        "1330:")[1].splitlines()[0]


@needs_radiance
def test_build_removes_the_other_kind_of_folder(reduced):
    proj = load_project(reduced)
    build_project(proj, ["F"], pictures=False)
    assert (proj.build_dir / "F@3").is_dir() and not (proj.build_dir / "F").exists()
    toml = reduced / "radtree.toml"
    toml.write_text(toml.read_text().replace('"louvers.realisations" = 3',
                                             '"louvers.realisations" = 1'))
    proj = load_project(reduced)
    build_project(proj, ["F"], pictures=False)
    assert (proj.build_dir / "F").is_dir()
    assert not list(proj.build_dir.glob("F@*"))


def test_annual_says_it_uses_the_first_crown(reduced):
    from radtree.annual.run import AnnualOptions, choose_scenarios

    proj = load_project(reduced)
    with_sc, _, notes = choose_scenarios(proj, AnnualOptions(with_scenario="F"))
    assert with_sc.name == "F"
    assert any("averages 3 random crowns" in n and "louvers.seed 1" in n for n in notes)


@needs_radiance
def test_convergence_checks_the_first_crown_only(reduced):
    from radtree.convergence import convergence_table

    proj = load_project(reduced)
    t = convergence_table(proj, options=RunOptions(scenarios=["F"], hours=["13:30"]),
                          ab_values=(1, 2))
    # the ladder asked for, plus the -ab simulate uses for this crown (6)
    assert t["scenario"].tolist() == ["F"] * 3 and t["ab"].tolist() == [1, 2, 6]
    assert t["facade_mean_lux"].iloc[2] > t["facade_mean_lux"].iloc[1] > t["facade_mean_lux"].iloc[0]


@pytest.mark.parametrize("value", [0, 65, 2.5])
def test_bad_realisations_are_named(tmp_path, value):
    p = copy_project(tmp_path / "proj", replace={r"^slat_size_m = 0.3":
                                                  f"slat_size_m = 0.3\nrealisations = {value}"})
    with pytest.raises(ConfigError, match="realisations"):
        load_project(p)


def test_bad_realisations_switch_is_named(reduced):
    toml = reduced / "radtree.toml"
    toml.write_text(toml.read_text().replace('"louvers.realisations" = 3',
                                             '"louvers.realisations" = 0'))
    # rejected when the project is read, before any build
    with pytest.raises(ConfigError, match=r"switches\.louvers\.realisations': got 0, expected ≥ 1"):
        load_project(reduced)
