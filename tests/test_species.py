"""The species library (materials/species/): values, sources, Radiance leaves, phenology."""

from __future__ import annotations

import hashlib
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import tomllib

from radtree.annual.phenology import Phenology, blend
from radtree.config import load_project
from radtree.engines.radiance.materials import material_text
from radtree.errors import ConfigError
from radtree.resources import folder, read_text
from radtree.site.frame import FacadeFrame
from radtree.trees.build import build_crown
from radtree.trees.louvers import LouverOptics
from radtree.trees.species import (
    CrownSize,
    crown_size,
    known_species,
    load_species,
    louvers_cover_fraction,
    species_library,
    species_tree,
    tree_defaults,
)
from tests.conftest import MENDOZA, copy_project
from tests.test_materials import entries

MENDOZA4 = ["morus_alba", "platanus_x_acerifolia", "fraxinus_excelsior", "melia_azedarach"]
TEMPERATE4 = ["tilia_cordata", "acer_platanoides", "quercus_robur", "aesculus_hippocastanum"]


def test_library_holds_the_eight_species_with_a_source_for_every_value() -> None:
    assert set(MENDOZA4 + TEMPERATE4) <= set(known_species())
    for key, sp in species_library().items():
        data = tomllib.loads(read_text("materials", f"species/{key}.toml"))
        for name, entry in data.items():
            if isinstance(entry, dict):
                assert entry["source"].strip(), (key, name)
                assert sp.sources[name] == entry["source"]
        assert len(sp.sources) == 16, (key, sorted(sp.sources))


def test_morus_alba_is_the_study_tree() -> None:
    sp = load_species("Morus alba")
    assert (sp.leaf_reflectance, sp.leaf_transmittance_diffuse,
            sp.leaf_transmittance_global) == (0.11, 0.05, 0.53)
    assert sp.leaf_size_m == 0.142 and sp.mean_leaf_tilt_deg == 31.8
    assert sp.permeability_leaf_on == 0.055
    assert sp.lai_leaf_on == pytest.approx(-2 * math.log(0.055), abs=0.005)   # 5.80
    assert "Mendoza study" in sp.sources["leaf_transmittance_global"]


@pytest.mark.parametrize("written", ["morus_alba", "MORUS ALBA", "white mulberry",
                                     "Platanus × acerifolia", "platanus x acerifolia",
                                     "Platanus_x_acerifolia"])
def test_lookup_by_key_scientific_or_common_name(written: str) -> None:
    assert load_species(written).key in ("morus_alba", "platanus_x_acerifolia")


def test_unknown_species_lists_the_known_ones() -> None:
    with pytest.raises(ConfigError) as err:
        load_species("Ginkgo biloba")
    text = str(err.value)
    assert "unknown species 'Ginkgo biloba'" in text
    for key in MENDOZA4 + TEMPERATE4:
        assert key in text


def test_leaf_rad_files_are_what_the_species_renders() -> None:
    node = folder("materials") / "species"
    for key, sp in species_library().items():
        text = (node / f"{key}.rad").read_text(encoding="utf-8")
        assert entries(text) == {sp.material_name: material_text(sp.leaf_material())}
    # Morus: C = 0.11 + 0.53 = 0.64, trans = 0.53/0.64 = 0.8281, tspec = 0.48/0.53 = 0.9057
    assert material_text(load_species("morus_alba").leaf_material()).splitlines()[-1] == \
        "7 0.64 0.64 0.64 0 0 0.8281 0.9057"
    assert material_text(load_species("tilia_cordata").leaf_material()).splitlines()[-1] == \
        "7 0.15 0.15 0.15 0 0 0.4 0"


def test_leaf_area_fraction_ramps_north_and_south() -> None:
    sp = load_species("tilia_cordata")          # out 115, full 140, fall 285 → 315
    north = 52.5
    assert sp.leaf_area_fraction(100, north) == 0.0
    assert sp.leaf_area_fraction(115, north) == 0.0
    assert sp.leaf_area_fraction(121.25, north) == pytest.approx(0.25)
    assert sp.leaf_area_fraction(127.5, north) == pytest.approx(0.5)
    assert sp.leaf_area_fraction(200, north) == 1.0
    assert sp.leaf_area_fraction(300, north) == pytest.approx(0.5)
    assert sp.leaf_area_fraction(315, north) == 0.0
    assert sp.leaf_area_fraction(360, north) == 0.0
    # the southern hemisphere: the same calendar 182 days later
    assert sp.leaf_area_fraction(127.5 + 182, -33.0) == pytest.approx(0.5)
    assert sp.leaf_area_fraction(300 + 182 - 365, -33.0) == pytest.approx(0.5)
    assert sp.leaf_area_fraction(20, -33.0) == 1.0       # January: southern summer
    assert sp.leaf_area_fraction(200, -33.0) == 0.0      # July: southern winter
    assert sp.lai(127.5, north) == pytest.approx(1.39 + 0.5 * (5.0 - 1.39))


def test_mendoza_mulberry_in_its_season() -> None:
    sp = load_species("morus_alba")   # north 76 → 106, 288 → 335; Mendoza = + 182 days
    lat = -32.89
    assert sp.leaf_area_fraction(357, lat) == 1.0          # 22 December, the study day
    assert sp.leaf_area_fraction(152, lat) == 0.0          # 1 June: bare
    assert sp.leaf_area_fraction(273, lat) == pytest.approx(0.5)   # 30 Sep: half way out
    assert sp.leaf_area_fraction(105 + 23.5, lat) == pytest.approx(0.5)   # leaf fall half way


def test_species_validated_on_creation() -> None:
    sp = load_species("morus_alba")
    with pytest.raises(ConfigError, match="leaf_transmittance_global.*exceeds 1"):
        replace(sp, leaf_transmittance_global=0.95)
    with pytest.raises(ConfigError, match="leaf_out_doy"):
        replace(sp, full_leaf_doy=50)
    with pytest.raises(ConfigError, match="no source given.*lai_leaf_on"):
        replace(sp, sources={k: v for k, v in sp.sources.items() if k != "lai_leaf_on"})
    with pytest.raises(ConfigError, match="expected one of spherical"):
        replace(sp, crown_shape="weeping")


def test_louvers_cover_fraction_matches_permeability() -> None:
    morus, melia = load_species("morus_alba"), load_species("melia_azedarach")
    for sp in (morus, melia):
        f = louvers_cover_fraction(sp.permeability_leaf_on, sp.leaf_transmittance_direct, 4)
        per_layer = 1 - f + f * sp.leaf_transmittance_direct
        assert per_layer ** 4 == pytest.approx(sp.permeability_leaf_on)
    # mulberry: slats 0.48 direct → nearly full cover (the study reading)
    assert tree_defaults(morus)["louvers"]["cover_fraction"] == round((1 - 0.055 ** 0.25) / 0.52, 4)
    assert tree_defaults(melia)["louvers"]["cover_fraction"] == round(1 - 0.0272 ** 0.25, 4)
    # the optics the project gives are the ones solved for: T 0.5 × 0.9 direct, 5 layers
    given = {"louvers": {"layers": 5, "transmittance": 0.5, "specular_fraction": 0.9}}
    assert tree_defaults(morus, given)["louvers"]["cover_fraction"] == \
        round((1 - 0.055 ** 0.2) / (1 - 0.45), 4)
    # a volume crown of given crossings keeps its density; without crossings it uses layers
    volume = {"arrangement": "volume", "crossings": 14.6}
    assert "cover_fraction" not in tree_defaults(morus, {"louvers": volume})["louvers"]
    assert tree_defaults(morus, {"louvers": {"arrangement": "volume"}})["louvers"][
        "cover_fraction"] == round((1 - 0.055 ** 0.25) / 0.52, 4)


def test_crown_size_from_inventory_row() -> None:
    sp = load_species("morus_alba")
    assert crown_size(sp, 12.5, 10.0, 3.0) == CrownSize(5.0, 4.75, 3.0)
    # no crown base: the species' oblate crown (vertical/horizontal 0.75) hung from the top
    c = crown_size(sp, 12.5, 10.0)
    assert (c.vertical_radius_m, c.base_height_m, c.height_m) == (3.75, 5.0, 12.5)
    with pytest.raises(ConfigError, match="T7: crown_base_m 13"):
        crown_size(sp, 12.5, 10.0, 13.0, where="T7")


def test_tree_species_fills_what_the_project_leaves_out(tmp_path: Path) -> None:
    proj = copy_project(tmp_path / "p", {
        r"^form = \"dome\".*$": 'form = "dome"\nspecies = "Melia azedarach"',
        r"^\[tree.homogeneous\]\nreflectance = 0.11\n": "[tree.homogeneous]\n",
        r"^reflectance = 0.11\ntransmittance = 0.5 .*\nspecular_fraction = 0.9 .*$": "",
    })
    p = load_project(proj)
    melia = load_species("melia_azedarach")
    lv = p.tree.louvers
    assert p.tree.species == "Melia azedarach"
    # filled from the species: leaf optics, tilt kept where given (30°), cover solved
    assert (lv.reflectance, lv.transmittance, lv.specular_fraction) == (0.09, 0.06, 0.0)
    assert lv.inclination_deg == 30.0 and lv.layers == 5
    assert lv.cover_fraction == round(1 - 0.0272 ** 0.2, 4)            # 0.5137
    assert LouverOptics.of(lv).tau_crown_direct == pytest.approx(0.0272, rel=1e-3)
    assert p.tree.homogeneous.reflectance == 0.09
    assert p.tree.homogeneous.permeability == 0.055                      # given in the file
    assert p.tree.perforated.openness == 0.06                            # given in the file
    # the crown carries the species' leaf and says so
    model = build_crown(p, "louvers", "dome", FacadeFrame(p.street.facade_azimuth_deg))
    assert material_text(model.materials["leaf"]).splitlines()[-1] == "7 0.15 0.15 0.15 0 0 0.4 0"
    assert model.notes[0].startswith("Species Melia azedarach (chinaberry, "
                                     "materials/species/melia_azedarach.toml)")
    assert melia.describe() in model.notes[0]


def test_no_species_changes_no_hash(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without a species, no ``species`` key enters the hashed text (hashes as before it
    existed); with one, it does and the hash changes."""
    import radtree.config.params_hash as hashing

    hashed: list[bytes] = []
    real = hashlib.sha256
    monkeypatch.setattr(hashing.hashlib, "sha256", lambda b=b"": hashed.append(b) or real(b))
    p = load_project(MENDOZA)
    assert p.tree.species is None
    plain = p.params_hash(p.scenarios[0])
    assert '"species"' not in hashed[-1].decode()
    q = load_project(MENDOZA, {"tree.species": "morus_alba"})
    assert q.params_hash(q.scenarios[0]) != plain
    assert '"species": "morus_alba"' in hashed[-1].decode()


def test_unknown_tree_species_names_the_field(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as err:
        load_project(MENDOZA, {"tree.species": "Ginkgo biloba"})
    assert "field 'tree.species': unknown species 'Ginkgo biloba' (known: acer_platanoides" \
        in str(err.value)


def test_phenology_hourly_fraction_and_beer_weights() -> None:
    morus = Phenology.of("morus_alba", -32.89)     # Mendoza: out 258 → full 288 (south)
    month, day, hour = np.array([9, 9, 12, 7]), np.array([30, 30, 22, 1]), \
        np.array([12.5, 0.5, 12.5, 12.5])
    f = morus.leaf_fraction(month, day, hour)
    # 30 Sep = day 273; 12:30 → t = 273 + 0.5/24; 00:30 → 273 − 11.5/24
    np.testing.assert_allclose(f, [(15 + 0.5 / 24) / 30, (15 - 11.5 / 24) / 30, 1.0, 0.0])
    leaf_area = 5.8 - 1.39                          # lai_leaf_on − lai_leaf_off
    assert morus.leaf_area == pytest.approx(leaf_area)
    w = morus.weight(np.array([0.0, 0.5, 1.0]))
    expect = (1 - math.exp(-0.5 * 0.5 * leaf_area)) / (1 - math.exp(-0.5 * leaf_area))
    np.testing.assert_allclose(w, [0.0, expect, 1.0])
    assert expect == pytest.approx(0.7507, abs=1e-4)
    on, off = np.array([[100.0, 100.0, 100.0]], np.float32), np.array([[300.0] * 3], np.float32)
    np.testing.assert_allclose(blend(on, off, w), [[300.0, 300 - 200 * expect, 100.0]],
                               rtol=1e-6)
    assert "leaves out from day 258, full leaf day 288, leaf fall days 105–152" in \
        morus.describe()


def test_species_tree_from_a_species_and_a_size() -> None:
    p = load_project(MENDOZA)
    sp = load_species("platanus_x_acerifolia")
    size = crown_size(sp, 14.0, 12.0, 4.0)                    # radius 6, semi-axis 5
    t = species_tree(p.tree, sp, size, keep=["louvers.layers", "louvers.inclination_deg"])
    assert (t.crown.radius_m, t.crown.vertical_radius_m, t.crown.base_height_m) == (6, 5, 4)
    assert t.crown.trunk_distance_m == p.tree.crown.trunk_distance_m
    lv = t.louvers
    assert (lv.reflectance, lv.transmittance, lv.specular_fraction) == (0.09, 0.06, 0.0)
    assert (lv.layers, lv.inclination_deg) == (5, 30.0)        # kept as the project has them
    assert LouverOptics.of(lv).tau_crown_direct == pytest.approx(0.218, rel=1e-3)
    assert t.homogeneous.permeability == 0.218 and t.perforated.openness == 0.218
    dense = replace(p.tree, louvers=replace(p.tree.louvers, arrangement="volume", crossings=9.0))
    assert species_tree(dense, sp).louvers.cover_fraction == 1.0          # its own density
    untouched = species_tree(p.tree, sp)
    assert untouched.crown == p.tree.crown and untouched.louvers.inclination_deg == 44.2


def test_species_line_gives_the_southern_sites_leaf_calendar() -> None:
    """The library's days are the northern hemisphere's; a southern site's note gives the
    days it uses (182 days later), a northern site's does not."""
    sp = load_species("morus_alba")
    south = sp.describe(-32.89)
    assert "leaves out day 76, full 106, fall 288–335 (northern hemisphere)" in south
    assert "at this southern site 182 days later: leaves out day 258, full 288, fall 105–152" \
        in south
    assert sp.describe(40.4) == sp.describe() and "southern" not in sp.describe(40.4)
    # the calendar the note prints is the one the leaf area follows: full leaf from day 288
    assert sp.leaf_area_fraction(288.0, -32.89) == 1.0
    assert sp.leaf_area_fraction(257.0, -32.89) == 0.0
