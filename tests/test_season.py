"""The leaf season from the species and the site's hemisphere (issue 37): no reference dates."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from radtree.annual.schedule import leaf_season
from radtree.cli import main
from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.site.starter import Location, new_project


def _project(tmp_path: Path, lat: float, lon: float, tz: str):
    out = new_project(tmp_path / f"p{lat:g}", where=Location(lat, lon, tz))
    return load_project(out.path)


def test_northern_and_southern_seasons_from_the_species(tmp_path: Path) -> None:
    """London plane (leaf-out days 76 → 106, fall 288 → 335, northern calendar): in leaf from
    the middle of leaf-out (day 91 = 1 April) to the middle of leaf fall (day 311 = 7 Nov);
    south of the equator 182 days later (30 September → 8 May)."""
    madrid = _project(tmp_path, 40.42, -3.70, "Europe/Madrid")
    assert madrid.tree.species == "platanus_x_acerifolia"
    s = leaf_season(madrid)
    assert (s.leaf_on, s.leaf_off) == ("04-01", "11-07")
    assert "northern hemisphere" in s.source and "Platanus" in s.source
    sydney = _project(tmp_path, -33.87, 151.21, "Australia/Sydney")
    s = leaf_season(sydney)
    assert (s.leaf_on, s.leaf_off) == ("09-30", "05-08")
    assert "southern hemisphere" in s.source
    # given dates and the project's own dates win, in that order
    assert leaf_season(madrid, "05-01", "10-01").leaf_on == "05-01"
    own = replace(madrid, tree=replace(madrid.tree, leaf_on="03-15", leaf_off="12-01"))
    assert (leaf_season(own).leaf_on, leaf_season(own).source) == \
        ("03-15", "[tree] leaf_on / leaf_off")


def test_between_the_tropics_the_user_states_the_season(tmp_path: Path) -> None:
    singapore = _project(tmp_path, 1.35, 103.82, "Asia/Singapore")
    with pytest.raises(ConfigError, match="latitude 1.35 lies between the tropics.*give "
                                          r"\[tree\] leaf_on / leaf_off"):
        leaf_season(singapore)
    from radtree.trees.species import load_species

    evergreen = replace(load_species("platanus_x_acerifolia"), tropical_phenology="evergreen")
    import radtree.annual.schedule as schedule
    import radtree.trees.species as species_mod

    orig = species_mod.load_species
    species_mod.load_species = lambda name: evergreen   # a library entry that states it
    try:
        s = schedule.leaf_season(singapore)
    finally:
        species_mod.load_species = orig
    assert (s.leaf_on, s.leaf_off) == ("01-01", "12-31") and "evergreen" in s.source


def test_annual_help_names_no_reference_dates() -> None:
    out = " ".join(CliRunner().invoke(main, ["annual", "--help"]).output.split())
    assert "10-15" not in out and "Mendoza" not in out and "Morus" not in out
    assert "species' phenology in the site's hemisphere" in out
