"""``radtree verify``: the physics suite, writing ``verify.csv``; exit status 1 on a failure."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from radtree.cli.errors import CHECK_FAILED
from radtree.cli.options import CONTEXT

GROUP_NAMES = ("layers", "spheres", "energy", "media", "agreement-dome", "agreement-free",
               "threephase", "annual", "honeybee", "energyplus", "gltf", "photo", "diagnose")


@click.command("verify", context_settings=CONTEXT)
@click.option("--full", is_flag=True,
              help="The long version: every row sampled until its 3 standard errors fit its "
                   "claim, scenarios A and B of the reduced dome and the free volume crown at "
                   "10:30, 12:30 and 14:30 against NumPy, at 12:30 against Radiance, the "
                   "three-phase closure, the annual method against point-in-time rtrace, the "
                   "EnergyPlus schedule against pyranometers, the photo round trip of a known "
                   "crown and the diagnose self-test.")
@click.option("--out", "-o", type=click.Path(dir_okay=False, path_type=Path),
              default=Path("verify.csv"), show_default=True, help="Where to write the table.")
@click.option("--page", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Also write the validation page (Markdown: output path, reference, "
                   "claim, tolerance, measured, status). Default with --full or --merge: "
                   "docs/validation.md.")
@click.option("--backward", multiple=True,
              help="Backward engine(s) to compare the forward engine with (default: every "
                   "available one).")
@click.option("--group", "groups", multiple=True, type=click.Choice(GROUP_NAMES),
              help="Run only these row groups (repeatable; default all): run groups as "
                   "separate processes and join their tables with --merge.")
@click.option("--merge", multiple=True, type=click.Path(exists=True, dir_okay=False,
                                                        path_type=Path),
              help="Trace nothing: join these verify tables (from --group runs) into the "
                   "page (repeatable).")
def verify_command(full: bool, out: Path, page: Path | None, backward: tuple[str, ...],
                   groups: tuple[str, ...], merge: tuple[Path, ...]) -> None:
    """Physics checks: uncollided transmission through random leaf layers against
    exp(−G·LAI/cos θ) and under floating spheres against its numerical integral, energy
    conservation, turbid, voxel and mist crowns, forward vs backward engines on the reduced
    Mendoza louvers dome and a free volume crown; then every output path beyond the engines:
    annual, Honeybee and EnergyPlus exports, glTF, the photo round trip, the diagnose
    self-test. Writes OUT (check, engine, expected, got,
    tolerance, claim, status, passed, reference, seconds)."""
    from radtree.verify.suite import read_checks, run_verify

    if merge:
        runs = [read_checks(p) for p in merge]
        checks = [c for run, _s in runs for c in run]
        seconds = max(s for _c, s in runs)
        command = "radtree verify --full"
        note = (f" wall clock: {len(merge)} row groups run side by side with `--group`, "
                f"{sum(s for _c, s in runs):.0f} s of runs in all, joined by `radtree verify "
                f"--merge`")
        page = page or Path("docs") / "validation.md"
    else:
        outcome = run_verify(out, full=full, backward=list(backward) or None,
                             groups=groups or None)
        checks, seconds, note = outcome.checks, outcome.seconds, ""
        command = "radtree verify" + (" --full" if full else "") + "".join(
            f" --group {g}" for g in groups)
        if page is None and full and not groups:
            page = Path("docs") / "validation.md"
    marks = {"pass": "ok  ", "fail": "FAIL", "unresolved": "??  "}
    for c in checks:
        click.echo(f"{marks[c.status]} {c.engine:8s} {c.check}: expected {c.expected:.5g}, "
                   f"got {c.got:.5g} (± {c.tolerance:.3g}"
                   + ("" if c.claim is None or c.tolerance <= c.claim else
                      f", wider than the claim ± {c.claim:.3g}: unresolved") + ")")
    n = len(checks)
    bad = sum(c.status == "fail" for c in checks)
    unresolved = sum(c.status == "unresolved" for c in checks)
    click.echo(f"{n - bad - unresolved}/{n} checks passed, {unresolved} unresolved, {bad} "
               f"failed in {seconds:.0f} s" + ("" if merge else f" → {out}"))
    if page is not None:
        from radtree.verify.page import write_page

        click.echo(f"validation page → {write_page(page, checks, command, seconds, note)}")
    if bad:
        sys.exit(CHECK_FAILED)
