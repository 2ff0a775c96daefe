"""The report section on the study's method: its tests of SPEC §7's findings and the setting
it names as their cause, on a method table whose hourly values are built from the measured
ones (so each finding's test has a known answer)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from radtree.config import load_project
from radtree.measurements import hourly_grid_means
from radtree.report.sections import Section, render_section
from radtree.report.sections.method import method_section_data
from radtree.stats import nrmse
from radtree.verify.compare import MENDOZA


def _table(m: pd.Series) -> pd.DataFrame:
    """study: A = measured − 50 lx, B/C/E far below, D spikes; no threshold: A at half the
    measured values (so "A close" vanishes with the threshold change)."""
    low = np.array([h in ("10:30", "11:30", "15:30", "16:30") for h in m.index])
    study = {"A": m - 50.0, "B": np.where(low, m - 600.0, m - 100.0), "C": m * 0.8,
             "D": np.where(m.index == "12:30", m * 2.0, m * 0.1), "E": m * 0.02}
    rows = []
    for variant, values in (("study", study), ("no threshold", {**study, "A": m * 0.5})):
        for radius in ((4.0, 2.0) if variant == "study" else (4.0,)):
            for name, v in values.items():
                for t, x in zip(m.index, np.asarray(v, float)):
                    rows.append({"variant": variant, "radius_m": radius, "scenario": name,
                                 "time": t, "lux": x, "stderr": 1.0, "engine": "forward",
                                 "photons": 1000, "slat_m": 0.3})
    return pd.DataFrame(rows)


def test_findings_and_their_cause(tmp_path):
    proj = load_project(MENDOZA)
    m = hourly_grid_means(proj.measured)
    root = tmp_path / "p"
    (root / "method").mkdir(parents=True)
    _table(m).to_csv(root / "method" / "hourly.csv", index=False)
    from dataclasses import replace

    data = method_section_data(replace(proj, root=root), tmp_path / "report")
    got = {f[0].split(":")[0]: (f[1], f[3]) for f in data["findings"]}
    assert got["A follows the measured day, differences below 120 lx"] == (
        "yes", "vanishes with splitting + killing → Russian roulette (unbiased), same beam")
    assert got["B far below the measurements at the low-sun hours (≈ 500 lx)"][0] == "yes"
    assert got["C (traced) fits better than D (calculated)"] == ("yes", "holds under every variant")
    assert got["E (6 % shell) misses the reflected component at all hours"][0] == "yes"
    table = _table(m)
    study = table[(table["variant"] == "study") & (table["radius_m"] == 4.0)]
    fit = {k: nrmse(m.to_numpy(), g["lux"].to_numpy()) for k, g in study.groupby("scenario")}
    assert data["orders"][0][2] == " < ".join(sorted(fit, key=fit.get))
    assert got["Ordering by nRMSE"][0] == ("yes" if sorted(fit, key=fit.get) in (
        list("ABCED"), list("ACBED")) else "no")
    assert [r[0] for r in data["scan_orders"]] == ["2", "4"]
    assert (tmp_path / "report" / data["figure"]).exists()
    md = render_section(Section("method", data), html=False)
    assert "| study | A | " + " | ".join(f"{x - 50:.0f}" for x in m) in md
