"""``radtree --help`` lists every command from :data:`radtree.cli.SUMMARIES` without importing
the commands (trimesh, scikit-image, matplotlib …): the same lines click would write from the
commands themselves, at every width."""

from __future__ import annotations

import subprocess
import sys

import click
import pytest
from click.utils import make_default_short_help

from radtree.cli import COMMANDS, SUMMARIES, main


def test_every_command_has_its_summary():
    assert set(SUMMARIES) == set(COMMANDS)


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_summary_gives_the_commands_own_short_help(name):
    cmd = main.get_command(click.Context(main), name)
    assert cmd is not None
    for limit in (20, 33, 45, 60, 80, 120, 400):
        assert make_default_short_help(SUMMARIES[name], limit) == cmd.get_short_help_str(limit)


def test_help_lists_the_commands_without_importing_them():
    code = ("import sys\nfrom radtree.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith('radtree.cli.')))\n"
            "print('trimesh' in sys.modules, 'matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert "Commands:\n  annual        Annual daylight (8760 h) with a deciduous tree" in out
    assert "  verify        Physics checks: uncollided transmission through" in out
    imported, heavy = out.strip().splitlines()[-2:]
    assert "radtree.cli.annual" not in imported and "radtree.cli.verify" not in imported
    assert heavy == "False False"
