"""Finished hours on disk: ``results/parts/<scenario>_<HHMM>_<engine>_<hash>.csv``, each with
its manifest ``<part>.csv.json`` (``bytes``, ``sha256``, ``rows``, ``radtree_version``).

A part is reused only when its manifest matches the file byte for byte and its rows are the
scenario's hour; a truncated or hand-edited part, or one without a manifest (an interrupted
write, an older radtree), is reported and recomputed. Both files are written atomically, the
part first, so a part never has a manifest it does not match.
"""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

import radtree
from radtree.fileio import atomic_path, write_text
from radtree.pipeline.manifest import file_sha256
from radtree.results_schema import REQUIRED_COLUMNS


def manifest_path(part: Path) -> Path:
    """``<part>.json`` beside the part."""
    return part.with_name(part.name + ".json")


def write_part(part: Path, table: pd.DataFrame) -> None:
    """Write one hour's rows to ``part`` and then its manifest, both atomically."""
    with atomic_path(part) as tmp:
        table.to_csv(tmp, index=False)
        stamp = {"bytes": tmp.stat().st_size, "sha256": file_sha256(tmp), "rows": len(table),
                 "radtree_version": radtree.__version__}
    write_text(manifest_path(part), json.dumps(stamp, indent=1))


def check_part(part: Path, scenario: str, time: str, params_hash: str
               ) -> tuple[pd.DataFrame | None, str]:
    """``(rows, "")`` for a sound part of ``scenario`` at ``time`` (HH:MM), else ``(None, why)``
    — why it cannot be reused (missing, no manifest, truncated, changed, wrong rows)."""
    if not part.is_file():
        return None, "missing"
    try:
        stamp = json.loads(manifest_path(part).read_text(encoding="utf-8"))
        want_bytes, want_sha, want_rows = int(stamp["bytes"]), str(stamp["sha256"]), int(
            stamp["rows"])
    except (OSError, ValueError, KeyError, TypeError):
        return None, "has no valid manifest (an interrupted write or an older radtree)"
    if stamp.get("radtree_version") != radtree.__version__:
        return None, f"was written by radtree {stamp.get('radtree_version')} (this is " \
                     f"{radtree.__version__})"
    size = part.stat().st_size
    if size != want_bytes:
        return None, f"is {'truncated' if size < want_bytes else 'longer than written'} " \
                     f"({size} of {want_bytes} bytes)"
    if file_sha256(part) != want_sha:
        return None, "was changed after it was written (sha256 differs from its manifest)"
    try:
        rows = pd.read_csv(part, dtype={"scenario": str, "time": str, "params_hash": str,
                                       "building": str, "facade": str, "room": str})
    except (OSError, ValueError) as exc:
        return None, f"cannot be read ({exc})"
    missing = [c for c in REQUIRED_COLUMNS if c not in rows.columns]
    if missing or len(rows) != want_rows:
        return None, "does not hold the rows its manifest names"
    if not ((rows["scenario"] == scenario).all() and (rows["time"] == time).all()
            and (rows["params_hash"] == params_hash).all()):
        return None, f"holds rows of another scenario, hour or parameters than {scenario} " \
                     f"at {time}"
    return rows, ""
