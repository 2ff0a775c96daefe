"""The crown-model registry (radtree.config.crown_models, radtree.trees.registry): one list of
names for the schema, the CLI and the docs; builders imported by name; one line adds a model."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.cli.calibrate import calibrate_command
from radtree.config import Scenario
from radtree.config.crown_models import REGISTRY, CrownModel
from radtree.config.spec import spec_of
from radtree.errors import ConfigError
from radtree.trees.build import build_crown
from radtree.trees.homogeneous import build_homogeneous
from radtree.trees.louvers import build_louvers
from radtree.trees.model import no_crown
from radtree.trees.registry import (
    CROWN_MODELS,
    calibrated_models,
    crown_builder,
    crown_model,
    crown_model_rows,
)
from radtree.trees.turbid_voxels import build_turbid_crowns


def test_the_schema_and_the_cli_take_their_choices_from_the_registry():
    assert spec_of(Scenario, "model").choices == tuple(REGISTRY) == CROWN_MODELS
    assert CROWN_MODELS == ("homogeneous", "perforated", "louvers", "none")
    option = next(p for p in calibrate_command.params if p.name == "model")
    assert tuple(option.type.choices) == calibrated_models() == (
        "homogeneous", "perforated", "louvers")


def test_a_model_outside_the_registry_is_refused_on_load_and_by_the_registry():
    with pytest.raises(ConfigError, match="expected one of homogeneous, perforated, louvers, "
                                          "none"):
        Scenario(name="x", model="hedge")
    with pytest.raises(ConfigError) as exc:
        crown_model("hedge", source="radtree.toml")
    assert exc.value.field == "scenario.model" and "'hedge'" in str(exc.value)
    res = CliRunner().invoke(main, ["calibrate", ".", "--model", "none"])
    assert res.exit_code == 2 and "'none' is not one of" in res.output


def test_builders_are_resolved_by_representation_with_explicit_as_the_fallback():
    assert crown_builder("louvers") is build_louvers
    assert crown_builder("louvers", "turbid") is build_turbid_crowns   # spheroids or voxels
    assert crown_builder("louvers", "bsdf") is build_louvers   # the shell: pipeline.crown_bsdf
    assert crown_builder("homogeneous", "turbid") is build_homogeneous
    assert crown_builder("none", "turbid") is no_crown


def test_rows_for_the_docs_name_summary_and_capabilities():
    rows = {name: (summary, caps) for name, summary, caps in crown_model_rows()}
    assert list(rows) == list(CROWN_MODELS)
    assert rows["louvers"][1] == {"forms": ("dome", "free"),
                                  "representations": ("explicit", "turbid", "bsdf"),
                                  "calibrated": True}
    assert rows["homogeneous"][1]["representations"] == ("explicit",)
    assert rows["none"][1]["calibrated"] is False
    assert all(summary and not summary.endswith(".") for summary, _ in rows.values())


def test_build_crown_goes_through_the_registry(project, frame):
    """The model the registry names is what build_crown returns (same triangles and
    transmission as the builder called directly); the info's triangle count is the mesh's."""
    direct = build_homogeneous(project.tree, sensors=project.sensors, street=project.street,
                               frame=frame, form="dome", source=str(project.source))
    built = build_crown(project, "homogeneous", "dome", frame)
    assert built.model == "homogeneous" and built.triangles == direct.triangles > 100
    assert built.info["triangles"] == float(built.triangles)
    assert built.info["crown_transmission"] == direct.info["crown_transmission"]
    none = build_crown(project, "none", "free", frame)
    assert (none.meshes, none.recommended_ab, none.form) == ([], 2, "free")


def test_one_registry_line_adds_a_model(project, frame, monkeypatch):
    """A model registered by one line (here: the homogeneous builder under another name) is
    built by build_crown without any other change."""
    monkeypatch.setitem(REGISTRY, "shell", CrownModel(
        "shell", "a test copy of the homogeneous shell",
        {"explicit": "radtree.trees.homogeneous:build_homogeneous"}))
    copy = build_crown(project, "shell", "free", frame)
    same = build_crown(project, "homogeneous", "free", frame)
    assert copy.triangles == same.triangles and copy.info == same.info
    assert crown_model("shell").capabilities()["forms"] == ("dome", "free")
