"""What every engine returns, and the tidy results table built from it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

RESULT_COLUMNS = [
    "scenario", "model", "datetime", "time", "grid", "sensor", "row", "x", "y", "z",
    "lux", "lux_stderr", "engine", "params_hash",
]


@dataclass
class GridResult:
    """Illuminance (lux) per sensor of one grid for one hour; ``stderr`` the Monte Carlo
    standard error per sensor (None when the engine gives none)."""

    lux: np.ndarray
    stderr: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.lux = np.asarray(self.lux, float)
        if self.stderr is not None:
            self.stderr = np.asarray(self.stderr, float)
            if self.stderr.shape != self.lux.shape:
                raise ValueError("stderr must have the shape of lux")
