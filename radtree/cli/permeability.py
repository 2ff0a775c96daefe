"""``radtree permeability PROJECT``: scan a crown field against the crown's global permeability
and a scenario's fit (see :mod:`radtree.calibrate.scan`)."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT
from radtree.config import load_project


def _values(text: str) -> list[float]:
    try:
        if ":" in text:
            lo, hi, n = text.split(":")
            count = int(n)
            if count < 1:
                raise ValueError
            import numpy as np

            return [round(float(v), 6) for v in np.linspace(float(lo), float(hi), count)]
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise click.BadParameter(f"{text!r}: expected low:high:n or v1,v2,...") from None


@click.command("permeability", context_settings=CONTEXT)
@click.argument("project", type=click.Path(exists=True, path_type=Path))
@click.option("-s", "--scenario", default="A", show_default=True,
              help="Scenario whose fit is reported (its crown model is scanned).")
@click.option("--field", default="louvers.transmittance", show_default=True,
              help="Crown switch to vary, e.g. louvers.transmittance, louvers.layers, "
                   "homogeneous.permeability.")
@click.option("--values", "values_text", default="0.48:0.54:7", show_default=True,
              help="low:high:n or v1,v2,...")
@click.option("--rays", type=click.IntRange(64, 65536), default=2048, show_default=True,
              help="NumPy engine paths per sensor.")
def permeability_command(*, project: Path, scenario: str, field: str, values_text: str,
                         rays: int) -> None:
    """How a scenario's fit depends on the crown's global permeability (measured: 5–6 %).

    For each value of FIELD: the crown's global permeability against the open street
    (what `radtree calibrate --global` matches) and against the reference case's unobstructed global
    reference (flat ground to the horizon, sun + the stated clear sky), and the scenario's
    nRMSE / nMBE / r. Writes PROJECT/results/permeability_scan.csv and .png; `radtree report`
    shows them. Example:

      radtree permeability examples/mendoza-street -s A --values 0.48:0.54:7
    """
    from radtree.calibrate.scan import scan_permeability, write_scan

    values = _values(values_text)
    proj = load_project(project)
    scan = scan_permeability(proj, scenario, field, values, rays)
    csv, png = write_scan(scan, proj.results_dir)
    for line in scan.summary():
        click.echo(line)
    click.echo(f"Wrote {csv} and {png}")
