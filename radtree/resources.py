"""The files radtree ships beside its code: Jinja ``templates/`` and the Radiance ``materials/``.

Both are top-level folders of the checkout (beside ``radtree/``). A wheel carries them inside
the package, as ``radtree/templates/`` and ``radtree/materials/`` (``setup.py`` maps them), so
they are found the same way installed or not:

1. ``importlib.resources.files("radtree") / NAME`` — an installed wheel;
2. ``<checkout>/NAME`` beside the package — a checkout (editable install or ``PYTHONPATH``).

    from radtree.resources import template_environment, material_text
    template_environment().get_template("Makefile.j2")
    material_text("paint")          # the text of materials/paint.rad
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from jinja2 import BaseLoader, Environment, StrictUndefined, TemplateNotFound

from radtree.errors import RadtreeError

if TYPE_CHECKING:
    from importlib.resources.abc import Traversable

FOLDERS = ("templates", "materials")


def folder(name: str) -> Traversable:
    """The shipped folder ``name`` ("templates" or "materials"), installed or in the checkout."""
    if name not in FOLDERS:
        raise ValueError(f"unknown resource folder {name!r} (known: {', '.join(FOLDERS)})")
    installed = resources.files("radtree") / name
    if installed.is_dir() and any(installed.iterdir()):   # an empty leftover folder is no copy
        return installed
    checkout = Path(__file__).resolve().parent.parent / name
    if checkout.is_dir():
        return checkout
    raise RadtreeError(f"radtree's {name}/ folder is missing: neither installed with the package "
                       f"nor at {checkout} (reinstall radtree)")


def _file(name: str, relative: str) -> Traversable:
    node = folder(name)
    for part in relative.split("/"):
        node = node / part
    return node


def read_text(name: str, relative: str) -> str:
    """The text of ``relative`` (``/``-separated) in the shipped folder ``name``."""
    node = _file(name, relative)
    if not node.is_file():
        raise RadtreeError(f"radtree's {name}/ has no file {relative}")
    return node.read_text(encoding="utf-8")


def material_files() -> list[str]:
    """Names of the Radiance material files in ``materials/`` (``*.rad``), sorted."""
    return sorted(p.name for p in folder("materials").iterdir() if p.name.endswith(".rad"))


def material_text(name: str) -> str:
    """The text of ``materials/<name>.rad``."""
    return read_text("materials", f"{name}.rad")


class _TemplateLoader(BaseLoader):
    """Jinja loader over :func:`folder` ("templates"): works from a wheel and a checkout."""

    def get_source(self, environment: Environment, template: str) -> tuple[str, None, Any]:
        node = _file("templates", template)
        if not node.is_file():
            raise TemplateNotFound(template)
        return node.read_text(encoding="utf-8"), None, lambda: True


def template_environment(autoescape: bool = False, **options: Any) -> Environment:
    """A Jinja environment over ``templates/`` with undefined names as errors.

    ``autoescape`` is for HTML; ``options`` go to :class:`jinja2.Environment` (e.g.
    ``trim_blocks``, ``keep_trailing_newline``)."""
    return Environment(loader=_TemplateLoader(), undefined=StrictUndefined,
                       autoescape=autoescape, **options)
