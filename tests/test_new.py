"""``radtree new``: a commented radtree.toml from one's own data, accepted by ``build`` as is."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest
import tomllib
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import Crown, Louvers, Sensors, Street, load_project
from radtree.config.spec import spec_of, table_fields, toml_name
from radtree.config.switches import TABLES
from radtree.errors import ConfigError
from radtree.site.starter import Location, new_project, read_inputs, site_facts
from tests.conftest import ROOT

EPW = ROOT / "examples" / "office-block" / "data" / "mendoza_generated.epw"
HAS_DISTRICT = importlib.util.find_spec("radtree.config.district") is not None


def _section(text: str, table: str) -> str:
    """The lines of ``[table]`` up to the next table header."""
    m = re.search(rf"^\[{re.escape(table)}\]\n(.*?)(?=^\[|\Z)", text, flags=re.M | re.S)
    assert m, f"no [{table}]"
    return m.group(1)


def test_new_from_an_epw_then_build(tmp_path: Path) -> None:
    folder = tmp_path / "proj"
    res = CliRunner().invoke(main, ["new", str(folder), "--epw", str(EPW)])
    assert res.exit_code == 0, res.output
    assert ("site: latitude -32.89, longitude -68.83, time zone UTC-3, elevation 750 m"
            in res.output)
    assert "SITE NOT GIVEN ON THE COMMAND LINE — latitude/longitude from the EPW" in res.output
    assert (folder / "data" / EPW.name).read_bytes() == EPW.read_bytes()
    text = (folder / "radtree.toml").read_text()
    # every field of every table, with its unit and default
    for table, cls in TABLES.items():
        if table == "office":
            continue
        body = _section(text, table)
        for f in table_fields(cls):
            if spec_of(cls, f.name) is not None:
                assert re.search(rf"^(# )?{toml_name(cls, f.name)} = ", body, flags=re.M), \
                    (table, f.name)
    assert "# width_m = 20.0   # m; a number > 0; default 20.0" in text
    assert "# reflectance = 0.11   # fraction; a number ≥ 0 and ≤ 1; default 0.11" in text
    assert 'species = "platanus_x_acerifolia"' in text
    assert 'weather = "epw"' in text
    # loads to the schema's defaults, the species filling the leaf optics
    p = load_project(folder)
    assert (p.site.latitude, p.site.longitude, p.site.utc_offset_hours) == (-32.89, -68.83, -3)
    assert p.street == Street() and p.tree.crown == Crown() and p.sensors == Sensors()
    assert p.tree.louvers.layers == Louvers().layers
    # hours: every whole hour with the sun ≥ 5° high on the southern summer solstice
    assert p.site.date == "2024-12-21" and p.site.hours[0] == "07:00" \
        and p.site.hours[-1] == "20:00"
    # … and build accepts it as written
    res = CliRunner().invoke(main, ["build", str(folder), "-s", "trees", "--no-pictures"])
    assert res.exit_code == 0, res.output
    assert "void trans leaf" in (folder / "build" / "trees" / "materials.rad").read_text()
    assert (folder / "build" / "trees" / "Makefile").is_file()


def test_new_office_template_without_epw_is_clear_sky(tmp_path: Path) -> None:
    out = new_project(tmp_path / "o", template="office",
                      where=Location(40.42, -3.70, "Europe/Madrid", 667.0))
    assert out.weather == "clear-sky" and out.site["latitude"] == 40.42
    text = out.path.read_text()
    assert "# bays = 3   # an integer ≥ 1 and ≤ 21; default 3" in _section(text, "office")
    p = load_project(out.path)
    assert p.office is not None and p.light.epw is None and p.light.weather == "clear-sky"
    assert not (tmp_path / "o" / "data" / "generated_clear_sky.epw").exists()
    assert p.site.time_zone == "Europe/Madrid" and p.site.utc_offset_hours == 1.0


def test_new_needs_a_site(tmp_path: Path) -> None:
    res = CliRunner().invoke(main, ["new", str(tmp_path / "x")])
    assert res.exit_code == 2
    assert "radtree new needs the site: give --lat LAT --lon LON" in res.output
    assert not (tmp_path / "x").exists()


def _inventory(tmp_path: Path) -> tuple[Path, Path]:
    trees = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": [lon, lat]},
         "properties": {"id": f"T{i}", "species": sp, "height_m": 12.0,
                        "crown_diameter_m": 8.0, "crown_base_m": 3.0}}
        for i, (lon, lat, sp) in enumerate([(-68.846, -32.889, "Morus alba"),
                                            (-68.845, -32.889, "morus_alba"),
                                            (-68.844, -32.889, "Platanus × acerifolia"),
                                            (-68.843, -32.889, "Ginkgo biloba")])]}
    tp = tmp_path / "trees.geojson"
    tp.write_text(json.dumps(trees))
    cp = tmp_path / "trees.csv"
    cp.write_text("id,lon,lat,species,height_m,crown_diameter_m,crown_base_m\n"
                  "A,-68.80,-32.80,Melia azedarach,8,6,2\nB,-68.90,-32.90,Melia azedarach,8,6,2\n")
    return tp, cp


def test_inputs_summarised_per_species(tmp_path: Path) -> None:
    tp, cp = _inventory(tmp_path)
    info = read_inputs(tp, None, None)
    assert info.lines() == ["4 trees — Morus alba: 1; morus_alba: 1; Platanus × acerifolia: 1; "
                            "Ginkgo biloba: 1 (not in the species library)"]
    site, why = site_facts(None, inputs=info)
    assert (site["latitude"], site["longitude"], site["time_zone"]) == \
        (-32.889, -68.8445, "America/Argentina/Mendoza")
    assert "looked up from the coordinates" in why and "elevation 0 m (ASSUMED" in why
    csv_info = read_inputs(cp, None, None)
    assert csv_info.lines() == ["2 trees — Melia azedarach: 2"]
    assert site_facts(None, inputs=csv_info)[0]["latitude"] == -32.85
    hb = tmp_path / "model.hbjson"
    hb.write_text(json.dumps({"type": "Model", "rooms": [{"identifier": "r1"},
                                                        {"identifier": "r2"}]}))
    assert read_inputs(None, None, hb).lines() == ["Honeybee model: 2 rooms"]
    bad = tmp_path / "bad.geojson"
    bad.write_text('{"type": "Feature"}')
    with pytest.raises(ConfigError, match="bad.geojson: cannot read the trees"):
        read_inputs(bad, None, None)


def test_new_with_a_tree_inventory(tmp_path: Path) -> None:
    tp, _ = _inventory(tmp_path)
    folder = tmp_path / "street"
    args = ["new", str(folder), "--trees", str(tp), "--epw", str(EPW)]
    res = CliRunner().invoke(main, args)
    if HAS_DISTRICT:   # [site] trees is read: new → build
        assert res.exit_code == 0, res.output
        assert "4 trees — Morus alba: 1; morus_alba: 1;" in res.output
        data = tomllib.loads((folder / "radtree.toml").read_text())
        assert data["site"]["trees"] == "data/trees.geojson"
        assert data["tree"]["species"] == "morus_alba"
        assert data["site"]["time_zone"] == "UTC-3"
    else:              # this reader does not know [site] trees yet: refused, nothing kept
        assert res.exit_code == 2, res.output
        assert "field 'site.trees': unknown field" in res.output
        assert not folder.exists()


def test_new_refuses_to_overwrite_and_bad_requests(tmp_path: Path) -> None:
    new_project(tmp_path / "a", epw=EPW)
    with pytest.raises(ConfigError, match="exists already"):
        new_project(tmp_path / "a", epw=EPW)
    with pytest.raises(ConfigError, match="give both --lat and --lon"):
        Location(latitude=40.0)
    with pytest.raises(ConfigError, match="'Europe/Madird': not a known IANA time zone"):
        Location(40.0, -3.7, "Europe/Madird")
    with pytest.raises(ConfigError, match="district template needs --trees"):
        new_project(tmp_path / "b", template="district")
    assert not (tmp_path / "b").exists()
    hb = tmp_path / "model.hbjson"
    hb.write_text('{"type": "Model", "rooms": []}')
    with pytest.raises(ConfigError, match="office template and --honeybee both build"):
        new_project(tmp_path / "c", honeybee=hb, template="office")


def test_site_from_inputs_and_epw(tmp_path: Path) -> None:
    tp, _ = _inventory(tmp_path)
    site, why = site_facts(EPW, inputs=read_inputs(tp, None, None))
    assert (site["latitude"], site["longitude"], site["time_zone"],
            site["elevation_m"]) == (-32.889, -68.8445, "UTC-3", 750.0)
    assert why.startswith("latitude/longitude the centroid of the inputs' coordinates; time zone")
    far = tmp_path / "far.geojson"
    far.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": [2.35, 48.85]},
         "properties": {"species": "tilia_cordata"}}]}))
    with pytest.raises(ConfigError, match="the EPW .* is for latitude -32.89, longitude -68.83, "
                       "more than 0.5° from the site"):
        site_facts(EPW, inputs=read_inputs(far, None, None))
    with pytest.raises(ConfigError, match="standard time UTC-3 h, but the time zone "
                       "Europe/Madrid has standard time UTC\\+1 h"):
        site_facts(EPW, inputs=read_inputs(tp, None, None),
                   where=Location(time_zone="Europe/Madrid"))
