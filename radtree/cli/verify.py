"""``radtree verify``: the physics suite, writing ``verify.csv``; exit status 1 on a failure."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from radtree.cli.errors import CHECK_FAILED
from radtree.cli.options import CONTEXT


@click.command("verify", context_settings=CONTEXT)
@click.option("--full", is_flag=True,
              help="The long version: more photons and leaf layers, scenarios A and B of the "
                   "reduced dome and the free volume crown at 10:30, 12:30 and 14:30 against "
                   "NumPy, at 12:30 against Radiance.")
@click.option("--out", "-o", type=click.Path(dir_okay=False, path_type=Path),
              default=Path("verify.csv"), show_default=True, help="Where to write the table.")
@click.option("--page", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Also write the validation page (Markdown: output path, reference, "
                   "claim, tolerance, measured, status). Default with --full: "
                   "docs/validation.md.")
@click.option("--backward", multiple=True,
              help="Backward engine(s) to compare the forward engine with (default: every "
                   "available one).")
def verify_command(full: bool, out: Path, page: Path | None,
                   backward: tuple[str, ...]) -> None:
    """Physics checks: uncollided transmission through random leaf layers against
    exp(−G·LAI/cos θ) and under floating spheres against its numerical integral, energy
    conservation, forward vs backward engines on the reduced Mendoza louvers dome and a free
    volume crown. Writes OUT (check, engine, expected, got, tolerance, passed)."""
    from radtree.verify.suite import run_verify

    outcome = run_verify(out, full=full, backward=list(backward) or None)
    marks = {"pass": "ok  ", "fail": "FAIL", "unresolved": "??  "}
    for c in outcome.checks:
        click.echo(f"{marks[c.status]} {c.engine:8s} {c.check}: expected {c.expected:.5g}, "
                   f"got {c.got:.5g} (± {c.tolerance:.3g}"
                   + ("" if c.claim is None or c.tolerance <= c.claim else
                      f", wider than the claim ± {c.claim:.3g}: unresolved") + ")")
    n, bad = len(outcome.checks), len(outcome.failed)
    unresolved = len(outcome.unresolved)
    click.echo(f"{n - bad - unresolved}/{n} checks passed, {unresolved} unresolved, {bad} "
               f"failed in {outcome.seconds:.0f} s → {outcome.path}")
    if page is None and full:
        page = Path("docs") / "validation.md"
    if page is not None:
        from radtree.verify.page import write_page

        command = "radtree verify" + (" --full" if full else "")
        click.echo(f"validation page → {write_page(page, outcome.checks, command, outcome.seconds)}")
    if bad:
        sys.exit(CHECK_FAILED)
