"""A crown XML's transmission blocks made reciprocal patch by patch
(:func:`radtree.engines.radiance.bsdf.reciprocal_patches`).

rmtxop/dctimestep (the three-phase chain) read the XML's "Transmission Front"; rtrace's
``BSDF`` material, tracing from the room, reads "Transmission Back" and applies reciprocity.
An XML whose two blocks are independent Monte Carlo estimates gives the two programs
different numbers (3.4 % on the frads room, ``tests/test_frads_crosscheck.py``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from radtree.engines.radiance.binaries import run
from radtree.engines.radiance.bsdf import (
    KEYS,
    klems_patch_rings,
    opposite_patches,
    reciprocal_patches,
    wrap_flux,
    wrap_klems,
)
from radtree.engines.radiance.threephase import read_matrix
from tests.conftest import needs_radiance


def random_flux(seed: int, scale: float = 2e-3) -> dict[str, np.ndarray]:
    """Four noisy flux matrices F[out, in] with a strong diagonal (gaps seen straight)."""
    rng = np.random.default_rng(seed)
    flux = {k: rng.random((145, 145)) * scale for k in KEYS}
    flux["tf"] += np.diag(rng.random(145) * 0.3)
    flux["tb"] += np.diag(rng.random(145) * 0.3)
    return flux


def test_reciprocal_patches_pairs_every_patch_keeps_r_and_loses_no_energy():
    _, lam = klems_patch_rings()
    m = opposite_patches()
    assert np.array_equal(m[m], np.arange(145)) and m[0] == 0 and m[1] == 5

    for scale in (1e-4, 6e-3):
        flux = random_flux(3, scale=scale)
        out = reciprocal_patches(flux)
        f = {k: out[k] / lam[:, None] for k in KEYS}
        np.testing.assert_allclose(f["tf"], f["tb"][np.ix_(m, m)].T, rtol=1e-12)
        for key in ("rf", "rb"):
            np.testing.assert_allclose(f[key], f[key][np.ix_(m, m)].T, rtol=1e-12)
        # every incident patch keeps its reflection; transmission is the mean of each pair,
        # scaled down only where T + R would exceed 1
        mean = 0.5 * (flux["tf"] / lam[:, None] + flux["tb"][np.ix_(m, m)].T / lam[None, :])
        for side in "fb":
            np.testing.assert_allclose(out[f"r{side}"].sum(axis=0),
                                       flux[f"r{side}"].sum(axis=0), rtol=1e-9)
            total = out[f"t{side}"].sum(axis=0) + out[f"r{side}"].sum(axis=0)
            assert total.max() <= 1.0 + 1e-12
        if scale < 1e-3:
            np.testing.assert_allclose(f["tf"], mean, rtol=1e-12)
        else:
            assert (flux["tf"].sum(axis=0) + flux["rf"].sum(axis=0)).max() > 1.0
            assert np.all(f["tf"] <= mean * (1 + 1e-12)) and not np.allclose(f["tf"], mean)
        # reciprocal data are left as they are
        again = reciprocal_patches(out)
        for key in KEYS:
            np.testing.assert_allclose(again[key], out[key], rtol=1e-9, atol=1e-15)


def _one_block(xml: Path, dest: Path, drop: str) -> Path:
    text = xml.read_text()
    for block in re.findall(r"<WavelengthData>.*?</WavelengthData>", text, flags=re.S):
        if re.search(r"<WavelengthDataDirection>\s*" + drop, block):
            text = text.replace(block, "")
    dest.write_text(text)
    return dest


def _btdf(xml: Path) -> np.ndarray:
    """rmtxop's matrix of the XML (``cm_loadBTDF``: "Transmission Front" as it stands, or
    "Transmission Back" through reciprocity when the front block is missing)."""
    return read_matrix(run(["rmtxop", "-ff", str(xml)]), "rmtxop")[:, :, 1]


@needs_radiance
def test_radiance_reads_a_reciprocal_xml_alike_from_either_block(tmp_path):
    """Radiance's own reciprocity (src/util/cmbsdf.c, ``cm_bsdf_recip``) turns the XML's
    back block into its front block: the map of :func:`opposite_patches` is Radiance's."""
    xml = wrap_flux(tmp_path / "r", random_flux(11), "recip", 0.1, 1.0, 1.0)
    front = _btdf(_one_block(xml, tmp_path / "front.xml", "Transmission Back"))
    back = _btdf(_one_block(xml, tmp_path / "back.xml", "Transmission Front"))
    assert np.abs(front - back).max() <= 1e-3 * front.max()
    # the two raw passes (no reciprocity imposed) are read differently
    raw = tmp_path / "raw"
    raw.mkdir()
    flux = random_flux(11)
    for key in KEYS:
        np.savetxt(raw / f"{key}.dat", flux[key], fmt="%.7e", delimiter="\t")
    plain = wrap_klems(raw, "raw", 0.1, 1.0, 1.0)
    front = _btdf(_one_block(plain, tmp_path / "f2.xml", "Transmission Back"))
    back = _btdf(_one_block(plain, tmp_path / "b2.xml", "Transmission Front"))
    assert np.abs(front - back).max() > 0.1 * front.max()
