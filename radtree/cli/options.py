"""Options and settings shared by several commands."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

CONTEXT: dict[str, Any] = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


def scenarios_option(f: Callable[..., Any]) -> Callable[..., Any]:
    """``-s/--scenario`` (repeatable) → a tuple ``scenarios``."""
    return click.option("-s", "--scenario", "scenarios", multiple=True,
                        help="Only this scenario (repeatable). Default: all.")(f)
