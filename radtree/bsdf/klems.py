"""Reading a Klems BSDF XML back (WINDOW 6 / LBNL ``BSDF-v1.4`` schema) and checking it.

``IncidentDataStructure = Columns``: the ``ScatteringData`` of a block lists 145 rows of 145
values, row = outgoing patch, column = incident patch, in sr⁻¹ (BTDF/BRDF values). The
projected solid angle of a patch of the ring [θ₁, θ₂] with n_φ patches is
Λ = π (sin²θ₂ − sin²θ₁) / n_φ; the hemispherical transmission (or reflection) for incident
patch i is Σ_o f[o, i] Λ_o.

Reciprocity (Helmholtz) in the Klems basis, with Λ the projected solid angles:
R_f[o, i] = R_f[i, o] (the same side), T_f[o, i] = T_b[i, o] (light from the front into
patch o behind equals light from behind along o back into i) — each up to Monte Carlo noise.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.errors import ConfigError as InputError

NS = {"w": "http://windows.lbl.gov"}
DIRECTIONS = {"Transmission Front": "tf", "Reflection Front": "rf",
              "Transmission Back": "tb", "Reflection Back": "rb"}


@dataclass(frozen=True)
class KlemsBsdf:
    """The four Klems matrices f[out, in] (sr⁻¹), the patches' projected solid angles Λ
    (sr, summing to π), their polar angles θ (degrees, patch centres) and the thickness (m)."""

    matrices: dict[str, np.ndarray]
    lambdas: np.ndarray
    theta_deg: np.ndarray
    thickness_m: float

    def hemispherical(self, key: str) -> np.ndarray:
        """Σ_o f[o, i] Λ_o for each incident patch i of component ``key`` (tf, rf, tb, rb)."""
        return self.lambdas @ self.matrices[key]

    def flux(self, key: str) -> np.ndarray:
        """Flux transfer F[o, i] = f[o, i] Λ_o (fraction of incident flux from i into o)."""
        return self.matrices[key] * self.lambdas[:, None]

    def diffuse_hemispherical(self, key: str) -> float:
        """Hemispherical value for light incident uniformly (Λ-weighted) from the hemisphere."""
        return float(self.hemispherical(key) @ self.lambdas / math.pi)

    def ring_exchange(self, key: str) -> np.ndarray:
        """The symmetric exchange W[r_o, r_i] = Σ Λ_o f[o, i] Λ_i summed over the patches of
        each θ ring (9 × 9 for Klems full): reciprocity makes W_rf and W_rb symmetric and
        W_tf = W_tbᵀ, whatever the azimuth convention of the incident patches, and the ring
        sums average the Monte Carlo noise of single patches."""
        rings = np.unique(self.theta_deg, return_inverse=True)[1]
        onehot = np.eye(rings.max() + 1)[rings]                   # (145, 9)
        w = self.matrices[key] * np.outer(self.lambdas, self.lambdas)
        return onehot.T @ w @ onehot

    def reciprocity_error(self, max_theta_deg: float = 90.0) -> dict[str, float]:
        """Largest |A − Bᵀ| / max(A) over the ring exchanges of the reciprocal pairs
        (rf, rfᵀ), (rb, rbᵀ), (tf, tbᵀ) (:meth:`ring_exchange`), on the rings whose centre
        is below ``max_theta_deg`` (grazing rays may leave a finite sample sideways)."""
        out = {}
        keep = np.unique(self.theta_deg) < max_theta_deg
        for name, a, b in (("rf", "rf", "rf"), ("rb", "rb", "rb"), ("t", "tf", "tb")):
            A = self.ring_exchange(a)[np.ix_(keep, keep)]
            B = self.ring_exchange(b).T[np.ix_(keep, keep)]
            out[name] = float(np.abs(A - B).max() / max(float(A.max()), 1e-30))
        return out

    def energy_excess(self) -> dict[str, float]:
        """max over incident patches of T + R − 1 (front: tf + rf, back: tb + rb); ≤ 0 for
        a passive layer."""
        return {side: float(np.max(self.hemispherical(f"t{side}") + self.hemispherical(
            f"r{side}")) - 1.0) for side in ("f", "b")}


def read_klems(path: Path) -> KlemsBsdf:
    """Parse a Klems-full XML written by wrapBSDF (or WINDOW); errors name the file."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"cannot read BSDF XML {path}: {exc}") from exc
    blocks = root.findall(".//w:AngleBasis/w:AngleBasisBlock", NS)
    if not blocks:
        raise InputError(f"{path}: no Klems AngleBasis (is it a tensor-tree XML?)")
    lambdas: list[float] = []
    thetas: list[float] = []

    def num(b: ET.Element, tag: str) -> float:
        text = b.findtext(tag, namespaces=NS)
        if text is None:
            raise InputError(f"{path}: an AngleBasisBlock without {tag.split(':')[-1]}")
        return float(text)

    for b in blocks:
        n = int(num(b, "w:nPhis"))
        lo = math.radians(num(b, "w:ThetaBounds/w:LowerTheta"))
        hi = math.radians(num(b, "w:ThetaBounds/w:UpperTheta"))
        lam = math.pi * (math.sin(hi) ** 2 - math.sin(lo) ** 2) / n
        lambdas += [lam] * n
        thetas += [num(b, "w:Theta")] * n
    size = len(lambdas)
    mats: dict[str, np.ndarray] = {}
    for blk in root.findall(".//w:WavelengthDataBlock", NS):
        key = DIRECTIONS.get((blk.findtext("w:WavelengthDataDirection", namespaces=NS) or "")
                             .strip())
        text = blk.findtext("w:ScatteringData", namespaces=NS) or ""
        values = np.array(text.replace(",", " ").split(), float)
        if key is None or values.size != size * size:
            raise InputError(f"{path}: a ScatteringData block of {values.size} values, "
                             f"expected {size} × {size}")
        mats[key] = values.reshape(size, size)
    thick = float(root.findtext(".//w:Material/w:Thickness", default="0", namespaces=NS))
    return KlemsBsdf(mats, np.array(lambdas), np.array(thetas), thick)
