"""Crown models: triangle counts, build times and direct permeabilities, each model × form.

Run: ``.venv/bin/python benchmarks/trees.py [PROJECT]`` (default: examples/mendoza-street).
Prints one table for the configured models, one for the slat size of the louvers, and one for
the two readings of the louvers optics. "permeability" is the direct (specular) crown
transmission seen by the façade sensors (cosine-weighted; see radtree.calibrate.direct).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from radtree.calibrate.direct import sensor_permeability
from radtree.config import load_project
from radtree.site.frame import FacadeFrame
from radtree.trees.build import apply_switches, build_crown

ROOT = Path(__file__).resolve().parents[1]


def row(cells: list[str], widths: list[int]) -> str:
    return "  ".join(c.rjust(w) for c, w in zip(cells, widths))


def main(project_path: Path) -> None:
    project = load_project(project_path)
    frame = FacadeFrame(project.street.facade_azimuth_deg)
    print(f"radtree crown models — {project.source}")
    head = ["form", "model", "triangles", "build s", "analytic direct", "traced permeability",
            "trace s", "-ab"]
    widths = [5, 12, 9, 8, 15, 19, 7, 3]
    print(row(head, widths))
    for form in ("dome", "free"):
        for model in ("homogeneous", "perforated", "louvers"):
            best = float("inf")
            for _ in range(2):
                built = build_crown(project, model, form, frame)
                best = min(best, built.build_seconds)
            t0 = time.perf_counter()
            perm = sensor_permeability(built, project, frame, 1024)
            dt = time.perf_counter() - t0
            print(row([form, model, str(built.triangles), f"{best:.3f}",
                       f"{built.info.get('direct_transmission', 0.0):.4f}", f"{perm:.4f}",
                       f"{dt:.2f}", str(built.recommended_ab)], widths))

    print("\nLouvers slat size (study reading, 4 layers):")
    head = ["form", "slat m", "slats", "triangles", "build s"]
    widths = [5, 6, 7, 9, 8]
    print(row(head, widths))
    for form in ("dome", "free"):
        for size in (0.14, 0.2, 0.3, 0.5):
            tree, _ = apply_switches(project.tree, {"louvers.slat_size_m": size})
            built = build_crown(project, "louvers", form, frame, tree)
            print(row([form, f"{size:g}", str(int(built.info["slat_count"])),
                       str(built.triangles), f"{built.build_seconds:.3f}"], widths))

    print("\nLouvers readings (4 layers): direct transmission per layer / crown, traced:")
    head = ["form", "reading", "T", "T_s", "cover", "tau layer", "tau crown", "traced", "slats"]
    widths = [5, 7, 5, 5, 5, 9, 9, 7, 6]
    print(row(head, widths))
    for form in ("dome", "free"):
        for reading in ("study", "gap"):
            tree, _ = apply_switches(project.tree, {"louvers.reading": reading})
            built = build_crown(project, "louvers", form, frame, tree)
            perm = sensor_permeability(built, project, frame, 1024)
            i = built.info
            print(row([form, reading, f"{i['slat_transmittance']:g}",
                       f"{i['slat_specular_transmittance']:g}", f"{i['cover_fraction']:g}",
                       f"{i['tau_layer_direct']:.4f}", f"{i['tau_crown_direct']:.4f}",
                       f"{perm:.4f}", str(int(i["slat_count"]))], widths))


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "examples" / "mendoza-street")
