"""Daylight coefficients × the year's sky and suns → hourly lux (the one product every annual
method and its replicates share; :mod:`radtree.annual.run`, :mod:`radtree.annual.uncertainty`)."""

from __future__ import annotations

import numpy as np

from radtree.annual.skymatrix import Suns
from radtree.light.units import PHOTOPIC_RGB, WHITE_EFFICACY

LUX = WHITE_EFFICACY * np.array(PHOTOPIC_RGB)  # lux per Radiance R, G, B


def combine(c_sky: np.ndarray, sky: np.ndarray, c_dir: np.ndarray, suns: Suns,
            c_ind: np.ndarray, verts: np.ndarray, weights: np.ndarray, n_hours: int
            ) -> tuple[np.ndarray, np.ndarray]:
    """(total, direct) lux, each (sensors, hours).

    ``c_sky`` (sensors, patches, 3), ``sky`` (patches, hours, 3); ``c_dir`` (sensors, suns,
    3); ``c_ind`` (sensors, patch vertices, 3) inter-reflected-sun coefficients indexed like
    :func:`reinhart_directions` (row 0, the nadir, zero); ``verts``/``weights`` (suns, 3).
    """
    n = c_sky.shape[0]
    total = np.zeros((n, n_hours), np.float64)
    for ch in range(3):
        total += LUX[ch] * (c_sky[:, :, ch].astype(np.float64) @ sky[:, :, ch].astype(np.float64))
    direct = np.zeros((n, n_hours), np.float64)
    if len(suns):
        d = (c_dir.astype(np.float64) @ LUX) * suns.radiance[None, :]
        direct[:, suns.hour_index] = d
        ind_lux = c_ind.astype(np.float64) @ LUX  # (sensors, vertices)
        ind = np.einsum("skj,kj->sk", ind_lux[:, verts], weights) * suns.radiance[None, :]
        total[:, suns.hour_index] += d + ind
    return total.astype(np.float32), direct.astype(np.float32)
