"""No reference-study residue (issue 37): a project elsewhere hears nothing of the reference
city, study, species or stand-in photo — in ``radtree new``'s file, the CLI output or the
report."""

from __future__ import annotations

import re
from pathlib import Path

import tomlkit
from click.testing import CliRunner

from radtree.cli import main

RESIDUE = re.compile(r"mendoza|mulberry|morus|\bstand-?in\b|reference (study|site)|"
                     r"the study\b|study's|cuyo", re.IGNORECASE)


def _run(*args: str) -> str:
    res = CliRunner().invoke(main, list(args))
    assert res.exit_code == 0, res.output
    return res.output


def test_a_project_in_madrid_hears_nothing_of_the_reference(tmp_path: Path) -> None:
    folder = tmp_path / "madrid"
    out = _run("new", str(folder), "--lat", "40.42", "--lon", "-3.70", "--tz", "Europe/Madrid")
    toml = folder / "radtree.toml"
    doc = tomlkit.parse(toml.read_text())
    doc["site"]["hours"] = ["09:00", "15:00"]
    doc["engine"]["rays"] = 32
    toml.write_text(tomlkit.dumps(doc))
    out += _run("build", str(folder), "--no-pictures")
    out += _run("simulate", str(folder), "--engine", "numpy")
    out += _run("report", str(folder))
    texts = {"cli": out, "radtree.toml": toml.read_text(),
             "index.md": (folder / "report" / "index.md").read_text(),
             "index.html": (folder / "report" / "index.html").read_text()}
    found = {name: sorted({m.group(0) for m in RESIDUE.finditer(t)})
             for name, t in texts.items()}
    assert not any(found.values()), found
