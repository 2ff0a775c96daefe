"""A photo fit that does not describe the photo stops the build (issue 37): the ring table and
the reason; ``[tree] accept_poor_fit = true`` builds it and says so."""

from __future__ import annotations

from dataclasses import replace

import pytest

from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.pipeline.build import built_scene
from tests.conftest import ROOT


def _scenario(accept: bool):
    p = load_project(ROOT / "examples" / "mendoza-street")
    sc = p.scenario("F-photo")
    sw = {**sc.switches, "tree.photo_zenith_deg": 80, "tree.photo_height_m": 1.0,
          "tree.accept_poor_fit": accept}
    return p, replace(sc, switches=sw)


def test_poor_fit_is_refused_with_the_ring_table() -> None:
    p, sc = _scenario(False)
    with pytest.raises(ConfigError) as err:
        built_scene(p, sc)
    text = str(err.value)
    assert "field 'tree.photo'" in text and "does not describe it" in text
    assert "gap-fraction RMS over the zenith rings 0.4" in text and "> 0.05" in text
    assert "zenith °   photo gap  model gap" in text and "71–80" in text
    assert "accept_poor_fit = true" in text


def test_accepted_poor_fit_builds_and_says_so() -> None:
    p, sc = _scenario(True)
    notes = built_scene(p, sc).notes
    assert any(n.startswith("POOR PHOTO FIT ACCEPTED") for n in notes)


def test_the_examples_photo_fit_is_good() -> None:
    p = load_project(ROOT / "examples" / "mendoza-street")
    notes = built_scene(p, p.scenario("F-photo")).notes
    assert not any("POOR PHOTO FIT" in n for n in notes)


def test_the_report_says_so_on_its_first_page() -> None:
    """The accepted poor fit's build note becomes the report's first headline line."""
    from types import SimpleNamespace

    from radtree.report.build import _warnings

    p, sc = _scenario(True)
    notes = built_scene(p, sc).notes
    data = SimpleNamespace(names=["F-photo", "A"], scenario=lambda n: SimpleNamespace(
        build={"notes": notes} if n == "F-photo" else {}))
    lines = _warnings(data)
    assert len(lines) == 1 and lines[0].startswith("WARNING — scenario F-photo: POOR PHOTO FIT "
                                                   "ACCEPTED ([tree] accept_poor_fit = true)")
