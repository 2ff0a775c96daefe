"""Any site on Earth (issue 37): radtree's site, time zone, weather and sun chain against pvlib.

12 sites (both hemispheres, the tropics, above 60°, both sides of the date line, daylight saving
north and south, a half-hour offset) × 3 dates × façades facing N, E, S, W, every daylight hour:
:mod:`radtree.verify.anywhere`. ``benchmarks/anywhere.py`` prints the worst case per site.
"""

from __future__ import annotations

import json
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import tomlkit
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import load_project
from radtree.light.hours import hour_states
from radtree.verify.anywhere import DATES, SITES, TOLERANCE, compare_site, worst_table


@pytest.fixture(scope="module")
def comparisons() -> list:
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as d:
        return [compare_site(p, date, Path(d) / f"{i}-{j}", rays=256)
                for i, p in enumerate(SITES) for j, date in enumerate(DATES)]


def test_daylight_hours_are_pvlibs(comparisons: list) -> None:
    """The whole hours radtree traces lie between pvlib's sunrise and sunset, at every site."""
    bad = [(c.place.name, c.date, c.daylight_note, c.hours) for c in comparisons
           if not c.hours_match]
    assert not bad
    assert sum(len(c.hours) for c in comparisons) == 435
    reykjavik_june = next(c for c in comparisons if c.place.name == "Reykjavik"
                          and c.date == "2024-06-21")
    assert reykjavik_june.hours[0] == "04:00" and reykjavik_june.hours[-1] == "23:00"


def test_sun_on_each_facade_is_pvlibs(comparisons: list) -> None:
    """The direct sun on N/E/S/W façades (time zone, daylight saving, date line, hemisphere,
    clear-sky DNI) equals pvlib's beam on the plane: within 0.5 % where it exceeds 100 lx."""
    rt = np.concatenate([c.radtree_direct.ravel() for c in comparisons])
    pv = np.concatenate([c.pvlib_direct.ravel() for c in comparisons])
    lit = pv > 100.0
    assert lit.sum() > 800
    assert np.max(np.abs(rt[lit] - pv[lit]) / pv[lit]) < 0.005
    assert np.max(np.abs(rt[~lit] - pv[~lit])) < 10.0


def test_total_against_pvlib_perez(comparisons: list) -> None:
    """The total façade illuminance against pvlib's Perez (1990) transposition.

    The issue asks for 10 % at every daylight hour; that is NOT met (benchmarks/anywhere.py
    prints it): radtree's sky is the Perez (1993) all-weather luminance distribution of
    Radiance's gendaylit, whose circumsolar light is spread over the sky where the 1990
    transposition model puts it into the sun's direction, so façades facing away from a high
    sun get ~2× pvlib's sky part, and façades facing a sun below 5° get less. What is held
    here is the measured agreement, so that a regression shows; ``benchmarks/anywhere_sky.py``
    compares the sky models alone (Perez 1993 in any form: 38–58 % of hour-façades within 10 %
    on the sky part; pvlib's own Hay–Davies, Reindl, Klucher, isotropic: 8–22 %)."""
    err = np.concatenate([c.rel_error.ravel() for c in comparisons])
    print("\n" + "\n".join(worst_table(comparisons)))
    assert np.median(err) < 0.05
    assert np.mean(err <= TOLERANCE) > 0.78
    mid = np.concatenate([np.repeat((c.sun_altitude_deg >= 15) & (c.sun_altitude_deg < 60), 4)
                          for c in comparisons])
    assert np.mean(err[mid] <= TOLERANCE) > 0.88 and err[mid].max() < 0.20


def test_madrid_from_radtree_new(tmp_path: Path) -> None:
    """The issue's consultant in Madrid: every daylight hour of 21 June lit, 09:00 included."""
    folder = tmp_path / "my-street"
    res = CliRunner().invoke(main, ["new", str(folder), "--lat", "40.42", "--lon", "-3.70",
                                    "--tz", "Europe/Madrid"])
    assert res.exit_code == 0, res.output
    assert "time zone Europe/Madrid" in res.output and "clear sky" in res.output
    doc = tomlkit.parse((folder / "radtree.toml").read_text())
    assert doc["site"]["date"] == "2024-06-21" and "09:00" in doc["site"]["hours"]
    doc["engine"]["rays"] = 64
    doc["scenario"] = [s for s in doc["scenario"] if s["name"] == "open"]
    (folder / "radtree.toml").write_text(tomlkit.dumps(doc))
    p = load_project(folder)
    states = {st.time: st for st in hour_states(p)}
    nine = states["09:00"]
    assert nine.datetime.utcoffset().total_seconds() == 7200   # CEST
    assert 20 < nine.sun.altitude_deg < 40 and nine.direct_normal_lux > 40000
    res = CliRunner().invoke(main, ["simulate", str(folder), "--engine", "numpy"])
    assert res.exit_code == 0, res.output
    import pandas as pd

    table = pd.read_csv(folder / "results" / "illuminance.csv")
    facade = table[table.grid == "facade"].groupby("time").lux.mean()
    assert set(facade.index) == set(p.site.hours) and (facade > 500).all(), facade
    manifest = json.loads((folder / "results" / "manifest.json").read_text())
    nine_w = next(w for w in manifest["weather"]["open"] if w["time"] == "09:00")
    assert "clear sky (pvlib" in nine_w["source"] and nine_w["direct_normal_lux"] > 40000
