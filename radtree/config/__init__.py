"""The project description: typed dataclasses (:mod:`.schema`, values typed by :mod:`.spec`),
the TOML reader (:mod:`.reader`) and the one registry of dotted keys (:mod:`.switches`).

Import the public names from here: ``from radtree.config import Project, load_project``.
"""

from radtree.config.bsdf import REPRESENTATIONS, CrownBsdf
from radtree.config.engine import ForwardParams, NumpyParams, RadianceParams
from radtree.config.reader import find_project_file, load_project, parse_project, set_dotted
from radtree.config.schema import (
    CROWN_MODELS,
    LOUVER_ARRANGEMENTS,
    LOUVER_READINGS,
    REFLECTION_MODES,
    SKY_CHOICES,
    TREE_FORMS,
    Crown,
    Dome,
    EngineParams,
    Homogeneous,
    Light,
    Louvers,
    Office,
    Perforated,
    Project,
    Scenario,
    Sensors,
    Site,
    Street,
    Tree,
    parse_time,
)
from radtree.config.spec import SchemaError, Spec
from radtree.config.switches import (
    FIELD,
    KEYS,
    PATH_FIELDS,
    PROJECT_SWITCH_SECTIONS,
    REFLECTION_GROUNDS,
    REFLECTION_VIEW_FACTORS,
    SWITCH,
    TREE_TABLES,
    Key,
    check_fields,
    check_key,
    check_switches,
    effective_project,
    known,
    lookup_key,
)

__all__ = [
    "CROWN_MODELS", "FIELD", "KEYS", "LOUVER_ARRANGEMENTS", "LOUVER_READINGS",
    "PATH_FIELDS", "PROJECT_SWITCH_SECTIONS", "REFLECTION_GROUNDS", "REFLECTION_MODES",
    "REFLECTION_VIEW_FACTORS", "SKY_CHOICES", "SWITCH", "TREE_FORMS", "TREE_TABLES", "Crown",
    "Dome", "EngineParams", "Homogeneous", "Key", "Light", "Louvers", "Office", "Perforated",
    "Project", "Scenario", "SchemaError", "Sensors", "Site", "Spec", "Street", "Tree",
    "check_fields", "check_key", "check_switches", "effective_project", "find_project_file",
    "known", "load_project", "lookup_key", "parse_project", "parse_time", "set_dotted",
    "REPRESENTATIONS", "CrownBsdf", "ForwardParams", "NumpyParams", "RadianceParams",
]
