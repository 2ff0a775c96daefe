"""Foliage clumping of the volume louvers crowns: the fields appended to ``[tree.louvers]``.

``clumping`` Ω (0.1–1, default 1 = no clumping: slats at random, every existing number
unchanged) — the crown's clumping index: slats are grouped in spherical clusters of radius
``cluster_radius_m`` (m) scattered at random through the crown, so that the mean gap
probability along a path L is exp(−G·u·Ω·L) (u the true leaf area density, G the slats' mean
projection; :mod:`radtree.trees.clumping`). ``clumping_fit`` (free crowns fitted to an upward
photo): estimate Ω from the photo — the Lang & Xiang (1986) log-averaging clumping index of its
ring × segment gap fractions, matched by the model's own — instead of keeping ``clumping``;
the fitted density is then the *true* one, LAI_true = LAI_eff / Ω.
"""

from __future__ import annotations

from dataclasses import field
from typing import Any

from radtree.config.spec import meta

#: the fields at their defaults (no clumping): left out of a scenario's parameter hash
CLUMPING_DEFAULTS: dict[str, Any] = {"clumping": 1.0, "cluster_radius_m": 0.5,
                                     "clumping_fit": False}


def clumping_fields() -> dict[str, Any]:
    """The dataclass fields (name → ``field``) appended to :class:`radtree.config.Louvers`."""
    return {
        "clumping": field(default=1.0, metadata=meta(0.1, 1.0)),
        "cluster_radius_m": field(default=0.5, metadata=meta(0.05, 5.0)),
        "clumping_fit": field(default=False),
    }
