"""Report tables as plain data: a header, which columns are numbers, rows of formatted text.

The HTML and Markdown templates render the same :class:`Table`; numbers are formatted here
once (``—`` for a missing value) so both outputs agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

MISSING = "—"


@dataclass
class Row:
    """One table row; a row with ``group`` set is a group heading spanning all columns."""

    cells: list[str] = field(default_factory=list)
    group: str | None = None


@dataclass
class Table:
    """A captioned table. ``numeric[i]`` marks column i as numbers (right-aligned)."""

    key: str
    caption: str
    header: list[str]
    numeric: list[bool]
    rows: list[Row] = field(default_factory=list)
    note: str = ""

    def __post_init__(self) -> None:
        if len(self.numeric) != len(self.header):
            raise ValueError(f"table {self.key}: {len(self.numeric)} numeric flags for "
                             f"{len(self.header)} columns")

    def add(self, *cells: Any) -> None:
        if len(cells) != len(self.header):
            raise ValueError(f"table {self.key}: {len(cells)} cells for {len(self.header)} "
                             "columns")
        self.rows.append(Row([str(c) for c in cells]))

    def add_group(self, label: str) -> None:
        self.rows.append(Row(group=label))

    @property
    def has_groups(self) -> bool:
        return sum(1 for r in self.rows if r.group is not None) > 1

    def to_markdown(self) -> str:
        """A GitHub-flavoured pipe table (group headings become bold rows)."""
        def esc(text: str) -> str:
            return text.replace("|", "\\|").replace("\n", " ")

        lines = ["| " + " | ".join(esc(h) for h in self.header) + " |",
                 "|" + "|".join("---:" if n else ":---" for n in self.numeric) + "|"]
        for row in self.rows:
            if row.group is not None:
                if not self.has_groups:
                    continue
                cells = [f"**{esc(row.group)}**"] + [""] * (len(self.header) - 1)
            else:
                cells = [esc(c) for c in row.cells]
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)


def is_missing(value: Any) -> bool:
    if value is None:
        return True
    try:
        return math.isnan(float(value))
    except (TypeError, ValueError):
        return False


def num(value: Any, decimals: int = 0) -> str:
    """A number with ``decimals`` places, ``—`` if missing."""
    if is_missing(value):
        return MISSING
    v = float(value)
    text = f"{v:.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return text


def lux(value: Any) -> str:
    """Illuminance in whole lux."""
    return num(value, 0)


def lux_pm(value: Any, stderr: Any) -> str:
    """``1234 ± 12`` when a Monte Carlo standard error is known, else ``1234``."""
    if is_missing(value):
        return MISSING
    if is_missing(stderr):
        return lux(value)
    return f"{lux(value)} ± {num(stderr, 0 if float(stderr) >= 1 else 1)}"


def seconds(value: Any) -> str:
    """A duration in seconds, with precision matched to its size."""
    if is_missing(value):
        return MISSING
    v = float(value)
    if v >= 100:
        return num(v, 0)
    if v >= 1:
        return num(v, 1)
    if v >= 0.01:
        return num(v, 2)
    return num(v, 4)


def text(value: Any) -> str:
    """Any value as text, ``—`` if missing or empty."""
    if is_missing(value) or str(value) == "":
        return MISSING
    return str(value)


def headline_table(path: str | Path) -> str:
    """The headline statistics of ``report/statistics.csv`` as aligned text (the CLI's summary)."""
    import pandas as pd

    stats = pd.read_csv(path, dtype={"scenario": str})
    if stats.empty:
        return "no measurements: no statistics (simulated values only)"
    cols = {"scenario": "scenario", "model": "model", "reflection": "reflection",
            "rmse": "nRMSE", "rmse_low": "low", "rmse_high": "high", "mbe": "nMBE", "r": "r",
            "r2": "R²", "n_hours": "n"}
    table = stats[list(cols)].rename(columns=cols)
    table["reflection"] = table["reflection"].fillna("")
    body = table.to_string(index=False, float_format=lambda v: f"{v:.3f}")
    return (body + "\nnRMSE, nMBE: normalised by the mean measured value (nMBE > 0: "
            "under-prediction); low–high: 95 % bootstrap interval on nRMSE")
