"""Per-sensor means and standard errors of the NumPy engine's path estimates, batch by batch."""

from __future__ import annotations

import numpy as np

from radtree.engines.base import GridResult
from radtree.engines.numpy.qmc import FirstDirections, replicate_stderr

__all__ = ["SensorTally"]


class SensorTally:
    """Per-sensor means and standard errors of path estimates ``x`` (k, columns), batch by
    batch: by replicates (``first``, Sobol' sampling) or by the per-path spread (Chan et al.'s
    merge of means and M2)."""

    def __init__(self, n_s: int, cols: int, first: FirstDirections | None):
        self.n_s, self.cols, self.first = n_s, cols, first
        cells = n_s * (first.r if first is not None else 1)
        self.sums = np.zeros((cols, cells))
        self.counts = np.zeros(cells)
        self.mean = np.zeros((cols, n_s))
        self.m2 = np.zeros((cols, n_s))

    def add(self, pid: np.ndarray, sensor: np.ndarray, x: np.ndarray) -> None:
        n_s = self.n_s
        if self.first is not None:
            cell = sensor * self.first.r + self.first.replicate(pid)
            self.counts += np.bincount(cell, minlength=len(self.counts))
            for c in range(self.cols):
                self.sums[c] += np.bincount(cell, x[:, c], minlength=len(self.counts))
            return
        count = self.counts
        cb = np.bincount(sensor, minlength=n_s).astype(float)
        has = cb > 0
        n_new = count + cb
        for c in range(self.cols):
            sb = np.bincount(sensor, x[:, c], minlength=n_s)
            mb = np.where(has, sb / np.where(has, cb, 1.0), 0.0)
            m2b = np.bincount(sensor, (x[:, c] - mb[sensor]) ** 2, minlength=n_s)
            mean, m2 = self.mean[c], self.m2[c]
            delta = mb - mean
            with np.errstate(invalid="ignore", divide="ignore"):
                self.mean[c] = np.where(has, mean + delta * cb / np.where(has, n_new, 1.0), mean)
                self.m2[c] = np.where(has, m2 + m2b + delta ** 2 * count * cb
                                      / np.where(has, n_new, 1.0), m2)
        self.counts = n_new

    def results(self, direct: np.ndarray) -> list[GridResult]:
        """One :class:`GridResult` per column, ``direct`` (lux per sensor) added."""
        out = []
        for c in range(self.cols):
            if self.first is not None:
                sums = self.sums[c].reshape(self.n_s, self.first.r)
                counts = self.counts.reshape(self.n_s, self.first.r)
                out.append(GridResult(direct + sums.sum(axis=1) / counts.sum(axis=1),
                                      replicate_stderr(sums, counts)))
            else:
                var = self.m2[c] / np.maximum(self.counts - 1.0, 1.0)
                out.append(GridResult(direct + self.mean[c],
                                      np.sqrt(np.maximum(var, 0.0) / self.counts)))
        return out
