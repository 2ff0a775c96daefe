"""A crown layer's BSDF with Radiance: rfluxmtx over Klems hemispheres → wrapBSDF → checkBSDF.

The recipe is genBSDF's (Radiance ``src/util/genBSDF.pl``, Klems branch), written out here
as argument lists because the pyradiance wheel ships rfluxmtx, rmtxop, wrapBSDF and
checkBSDF but not the genBSDF script:

* the system lies in ``z ≤ 0``, +z into the room (inside), width along x, height along y;
* the **front sender** is a polygon just outside the sample (``z = z_min − ε``, normal −z)
  with ``#@rfluxmtx u=-Y h=-kf``; the **back sender** just inside (``z = z_max + ε``,
  normal +z) with ``h=+kf``;
* the receivers are the two hemispheres of the sky as ``glow`` sources: ``receiver_face``
  (towards +z, ``h=-kf``, output ``face.dat``) and ``receiver_behind`` (towards −z,
  ``h=+kf``, ``behind.dat``);
* front pass: ``face.dat`` → T_f, ``behind.dat`` → R_f; back pass: ``behind.dat`` → T_b,
  ``face.dat`` → R_b; each transposed to photopic Y with ``rmtxop -fa -t -c 0.2651 0.6701
  0.0648``, made reciprocal patch by patch (:func:`reciprocal_patches`: rtrace reads the
  opposite side's block of what rmtxop reads) and wrapped with ``wrapBSDF -a kf -c``
  (``-c``: rfluxmtx gives flux factors, wrapBSDF divides by the projected solid angle to
  get BSDF values).

Unlike genBSDF the sample is one periodic cell tiled ``tiles`` × ``tiles`` times as Radiance
``instance``s of the cell octree; the senders cover the centre cell only, so light may move
sideways through the layer by up to (tiles − 1)/2 cells before it leaves the tiled area.
The optional tensor tree (``h=-sc<2^N>``, ``rttree_reduce``) follows genBSDF's ``-t4``.
"""

from __future__ import annotations

import logging
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from radtree.engines.radiance.binaries import FIXED_SEED, run
from radtree.engines.radiance.materials import material_text
from radtree.errors import EngineError
from radtree.fileio import write_text
from radtree.optics import KLEMS_FULL_RINGS, Material

log = logging.getLogger(__name__)

EPS = 1e-5
#: the way a Klems XML is assembled from the rfluxmtx passes, part of every sample's cache
#: key (2: made reciprocal patch by patch, :func:`reciprocal_patches`)
XML_VERSION = 2
#: photopic Y of Radiance RGB (the weights genBSDF passes to rmtxop -c)
Y_WEIGHTS = ("0.2651", "0.6701", "0.0648")


@dataclass(frozen=True)
class FluxSettings:
    """rfluxmtx sampling: ``samples`` rays per Klems patch (``-c``), ``ab``, ``ad``, ``lw``;
    ``tiles`` × ``tiles`` periodic copies of the cell; ``tensor_tree`` = 0 (Klems only) or
    the log2 resolution of an additional anisotropic tensor tree (genBSDF ``-t4 N``)."""

    samples: int = 500
    ab: int = 6
    ad: int = 2
    lw: float = 1e-3
    tiles: int = 9
    nproc: int = 1
    tensor_tree: int = 0

    def __post_init__(self) -> None:
        if self.samples < 1 or self.ab < 0 or self.ad < 1 or not self.lw > 0:
            raise ValueError("rfluxmtx settings: samples ≥ 1, ab ≥ 0, ad ≥ 1, lw > 0")
        if self.tiles < 1 or self.tiles % 2 == 0:
            raise ValueError(f"tiles must be odd (a centre cell), got {self.tiles}")
        if self.tensor_tree not in (0, 4, 5, 6):
            raise ValueError(f"tensor_tree must be 0 or 4–6, got {self.tensor_tree}")

    def options(self) -> list[str]:
        """rfluxmtx options: :data:`~radtree.engines.radiance.binaries.FIXED_SEED` (the same
        system and options give the same matrices), the ambient settings, ``-w-``, ``-n`` and
        ``-c``."""
        return [FIXED_SEED, "-ab", str(self.ab), "-ad", str(self.ad), "-lw", f"{self.lw:g}", "-w-",
                "-n", str(self.nproc), "-c", str(self.samples)]


@dataclass
class BsdfRun:
    """What one sample's run wrote: the XML, checkBSDF's report and the seconds taken."""

    xml: Path
    check: str
    seconds: float
    tensor_xml: Path | None = None


def _polygon(mat: str, name: str, corners: np.ndarray) -> str:
    coords = "\n".join("\t" + " ".join(f"{v:.6g}" for v in c) for c in corners)
    return f"{mat} polygon {name}\n0\n0\n{3 * len(corners)}\n{coords}\n"


def cell_text(polygons: dict[str, np.ndarray], materials: dict[str, Material]) -> str:
    """The cell: its materials and every polygon (``MAT polygon MAT.i``)."""
    out = ["# one periodic cell of the crown layer (radtree.trees.slab)\n"]
    out += [material_text(materials[name]) for name in polygons]
    for name, polys in polygons.items():
        out += [_polygon(name, f"{name}.{i}", p) for i, p in enumerate(polys)]
    return "\n".join(out)


def tiles_text(width: float, height: float, tiles: int, octree: str = "cell.oct") -> str:
    """``tiles`` × ``tiles`` instances of the cell octree, centred on the cell at the origin."""
    k = tiles // 2
    out = [f"# {tiles} x {tiles} periodic copies of {octree}\n"]
    for i in range(-k, k + 1):
        for j in range(-k, k + 1):
            out.append(f"void instance tile.{i + k}.{j + k}\n5 {octree} -t "
                       f"{i * width:.6g} {j * height:.6g} 0\n0\n0\n")
    return "\n".join(out)


def receivers_text(hemi: str = "kf") -> str:
    """genBSDF's two receiver hemispheres (``face.dat`` towards +z, ``behind.dat`` −z)."""
    return (f"#@rfluxmtx h=-{hemi}\n#@rfluxmtx u=-Y o=face.dat\n\n"
            "void glow receiver_face\n0\n0\n4 1 1 1 0\n\n"
            "receiver_face source f_receiver\n0\n0\n4 0 0 1 180\n\n"
            f"#@rfluxmtx h=+{hemi}\n#@rfluxmtx u=-Y o=behind.dat\n\n"
            "void glow receiver_behind\n0\n0\n4 1 1 1 0\n\n"
            "receiver_behind source b_receiver\n0\n0\n4 0 0 -1 180\n")


def sender_text(front: bool, width: float, height: float, z: float, hemi: str = "kf") -> str:
    """The front (outside, normal −z, ``h=-kf``) or back (inside, +z, ``h=+kf``) sender over
    the centre cell [0, width] × [0, height] at depth ``z``."""
    if front:
        corners = np.array([[0, 0, z], [0, height, z], [width, height, z], [width, 0, z]])
        return f"#@rfluxmtx u=-Y h=-{hemi}\n\n" + _polygon("void", "fwd_sender", corners)
    corners = np.array([[0, 0, z], [width, 0, z], [width, height, z], [0, height, z]])
    return f"#@rfluxmtx u=-Y h=+{hemi}\n\n" + _polygon("void", "bwd_sender", corners)


def write_system(folder: Path, polygons: dict[str, np.ndarray], materials: dict[str, Material],
                 width: float, height: float, thickness: float, tiles: int) -> None:
    """cell.rad → cell.oct, tiles.rad → system.oct, senders and receivers in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    write_text(folder / "cell.rad", cell_text(polygons, materials))
    run(["oconv", "cell.rad"], cwd=folder, stdout_path=folder / "cell.oct")
    write_text(folder / "tiles.rad", tiles_text(width, height, tiles))
    run(["oconv", "tiles.rad"], cwd=folder, stdout_path=folder / "system.oct")
    write_text(folder / "receivers.rad", receivers_text())
    write_text(folder / "fsender.rad", sender_text(True, width, height, -thickness - EPS))
    write_text(folder / "bsender.rad", sender_text(False, width, height, EPS))


def _to_y(folder: Path, src: str, dest: str) -> None:
    """rmtxop -fa -t -c (photopic Y) of an rfluxmtx output, header removed (getinfo -)."""
    data = run(["rmtxop", "-fa", "-t", "-c", *Y_WEIGHTS, src], cwd=folder)
    body = run(["getinfo", "-"], stdin=data, cwd=folder)
    (folder / dest).write_bytes(body)


def flux_commands(settings: FluxSettings) -> list[list[str]]:
    """The two rfluxmtx runs (front, back) as argument lists (run in the sample folder)."""
    return [["rfluxmtx", *settings.options(), "-fd", sender, "receivers.rad", "-i",
             "system.oct"] for sender in ("fsender.rad", "bsender.rad")]


PASSES = (("face.dat", "behind.dat", "tf", "rf"), ("behind.dat", "face.dat", "tb", "rb"))
KEYS = ("tf", "rf", "tb", "rb")


def flux_passes(folder: Path, settings: FluxSettings) -> None:
    """Both rfluxmtx passes in ``folder`` (after :func:`write_system`): ``tf.dat``,
    ``rf.dat``, ``tb.dat``, ``rb.dat``, photopic flux factors F[out, in]. Each command line is
    logged (INFO) before it runs."""
    for cmd, (trans, refl, tkey, rkey) in zip(flux_commands(settings), PASSES):
        log.info(" ".join(cmd))
        run(cmd, cwd=folder)
        _to_y(folder, trans, f"{tkey}.dat")
        _to_y(folder, refl, f"{rkey}.dat")


def wrap_klems(folder: Path, name: str, thickness: float, width: float, height: float,
               comment: str = "") -> Path:
    """wrapBSDF of the four ``*.dat`` flux matrices in ``folder`` → ``folder/<name>.xml``."""
    parts = [arg for key in KEYS for arg in (f"-{key}", f"{key}.dat")]
    fields = f"t={thickness:.6g};w={width:.6g};h={height:.6g};n={name};m=radtree"
    argv = ["wrapBSDF", "-a", "kf", "-c", "-u", "meter", "-f", fields, *parts]
    if comment:
        argv += ["-C", comment]
    xml = folder / f"{name}.xml"
    tmp = xml.with_name(xml.name + ".tmp")
    run(argv, cwd=folder, stdout_path=tmp)
    os.replace(tmp, xml)
    return xml


def klems_bsdf(folder: Path, settings: FluxSettings, name: str, thickness: float,
               width: float, height: float, comment: str = "") -> BsdfRun:
    """Run both rfluxmtx passes in ``folder`` (after :func:`write_system`) and wrap the four
    Klems matrices, made reciprocal (:func:`wrap_flux`), into ``folder/<name>.xml`` (sample
    ``thickness``, ``width``, ``height`` in m); checkBSDF must accept it."""
    t0 = time.perf_counter()
    flux_passes(folder, settings)
    flux = {key: np.loadtxt(folder / f"{key}.dat", ndmin=2) for key in KEYS}
    xml = wrap_flux(folder, flux, name, thickness, width, height, comment)
    return BsdfRun(xml, check_bsdf(xml), time.perf_counter() - t0)


def klems_patch_rings() -> tuple[np.ndarray, np.ndarray]:
    """(ring index, projected solid angle Λ in sr) of each of the 145 Klems patches."""
    ring, lam = [], []
    for k, (lo, hi, _, n) in enumerate(KLEMS_FULL_RINGS):
        a = math.pi * (math.sin(math.radians(hi)) ** 2 - math.sin(math.radians(lo)) ** 2) / n
        ring += [k] * n
        lam += [a] * n
    return np.array(ring), np.array(lam)


def reciprocal_rings(flux: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Flux matrices F[out, in] (``tf rf tb rb``) rescaled block by block (ring of out × ring
    of in) so that their ring exchanges W = Σ F[o, i] Λ_i obey Helmholtz reciprocity exactly:
    W_rf and W_rb symmetric, W_tf = W_tbᵀ. Needed when the columns of different incident
    rings come from different samples (:func:`klems_bsdf_rings`): a pair of blocks (light
    scattered from ring i into ring o, and back) comes from the two rings' samples and is
    set to the smaller of the two, so that every factor is ≤ 1 and no incident patch gains
    energy (the thin grazing samples transmit nearly everything undeviated: the mean would
    push their T + R above 1). The azimuthal structure inside a block is kept. Inside one
    ring the pair is one sample seen from both sides and differs by Monte Carlo noise only."""
    ring, lam = klems_patch_rings()
    onehot = np.eye(ring.max() + 1)[ring]

    def exchange(f: np.ndarray) -> np.ndarray:
        return onehot.T @ (f * lam[None, :]) @ onehot

    def scaled(f: np.ndarray, w: np.ndarray, target: np.ndarray) -> np.ndarray:
        full = w > 0
        factor = np.where(full, target / np.where(full, w, 1.0), 1.0)
        return f * factor[np.ix_(ring, ring)]

    out = dict(flux)
    for a, b in (("tf", "tb"), ("rf", "rf"), ("rb", "rb")):
        wa, wb = exchange(flux[a]), exchange(flux[b])
        target = np.minimum(wa, wb.T)
        out[a] = scaled(flux[a], wa, target)
        if b != a:
            out[b] = scaled(flux[b], wb, target.T)
    return out


def opposite_patches() -> np.ndarray:
    """For each Klems patch the patch of its ring whose azimuth is 180° away: the reciprocity
    map of Radiance's Klems library (``src/util/cmbsdf.c``, ``recip_in_from_out`` /
    ``recip_out_from_in`` over the incident/outgoing vectors of ``src/common/bsdf_m.c``)."""
    out, first = [], 0
    for _, _, _, n in KLEMS_FULL_RINGS:
        out += [first + (j + n // 2) % n for j in range(n)]
        first += n
    return np.array(out)


def _ratio(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.divide(a, b, out=np.zeros_like(a), where=b > 0)


def _scale_symmetric(b: np.ndarray, col: np.ndarray) -> np.ndarray:
    """z_o b[o, i] z_i (b symmetric) whose column sums are ``col``: the symmetric form of the
    Sinkhorn–Knopp iteration, z ← √(z ⊙ col / b z) (Sinkhorn & Knopp 1967; Knight, SIAM J.
    Matrix Anal. Appl. 30, 2008 — both cited from memory)."""
    z = np.where(col > 0, 1.0, 0.0)
    for _ in range(1000):
        z_new = np.sqrt(z * _ratio(col, b @ z))
        if np.allclose(z_new, z, rtol=1e-12, atol=0.0):
            break
        z = z_new
    return z_new[:, None] * b * z_new[None, :]


def reciprocal_patches(flux: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Flux matrices F[out, in] = f[out, in] Λ_out (``tf rf tb rb``) made reciprocal patch by
    patch: f_tf[o, i] = f_tb[m(i), m(o)], f_rf[o, i] = f_rf[m(i), m(o)], the same for rb,
    with m = :func:`opposite_patches`; each pair is set to its mean. Reflection is then
    scaled, one factor per patch (symmetric Sinkhorn), so that every incident patch keeps the
    reflectance its pass gave it (the column sums Σ_o F[o, i], exact for a deterministic
    layer: each ray's energy is tallied in its column; the mean alone would mix in the noisy
    row sums). Transmission keeps the mean (a per-patch scaling of both sides would bias the
    undeviated peak low by the noise of the two estimates), scaled down only where T + R
    would exceed 1, element (o, i) by the smaller factor of its two incident patches.

    Radiance reads one XML two ways: rmtxop/dctimestep take "Transmission Front" as it
    stands (``cm_loadBTDF``), while rtrace's ``BSDF`` material traces from the viewer and
    looks the pair up in the block of the opposite side ("Transmission Back" for a ray from
    the back), assuming reciprocity (``src/rt/m_bsdf.c``, ``sample_sdf``). The two passes of
    a sample are independent Monte Carlo estimates (and a chord envelope's columns come from
    different rings' samples): left apart, the three-phase chain and a direct rtrace of the
    same crown differ by their noise (3.4 % on the frads room of
    ``tests/test_frads_crosscheck.py``, ≤ 1 % once reciprocal,
    ``benchmarks/threephase_reciprocity.py``)."""
    _, lam = klems_patch_rings()
    m = opposite_patches()
    both = np.outer(lam, lam)

    def recip(f: np.ndarray) -> np.ndarray:
        return f[np.ix_(m, m)].T

    f = {k: flux[k] / lam[:, None] for k in KEYS}
    out = {}
    for key in ("rf", "rb"):
        # b[o, i] = Λ f[m(o), i] Λ is symmetric for a reciprocal f; its column sums are Λ R
        b = (0.5 * (f[key] + recip(f[key])) * both)[m]
        out[key] = _scale_symmetric(b, flux[key].sum(axis=0) * lam)[m] / both
    tf = 0.5 * (f["tf"] + recip(f["tb"]))

    def keep(t: np.ndarray, r: np.ndarray) -> np.ndarray:
        total = lam @ t + lam @ r
        return np.where(total > 1.0, _ratio(1.0 - lam @ r, lam @ t), 1.0).clip(0.0, 1.0)

    cf, cb = keep(tf, out["rf"]), keep(recip(tf), out["rb"])
    out["tf"] = tf * np.minimum(cf[None, :], cb[m][:, None])
    out["tb"] = recip(out["tf"])
    return {k: out[k] * lam[:, None] for k in KEYS}


def klems_bsdf_rings(folder: Path, *, ring_folders: list[Path], settings: FluxSettings,
                     name: str, thickness: float, width: float, height: float,
                     comment: str = "") -> BsdfRun:
    """One Klems XML from one sample per incident θ ring: both rfluxmtx passes in each of
    ``ring_folders`` (after :func:`write_system`), the columns of ring k's incident patches
    taken from ring k's run, made reciprocal (:func:`reciprocal_rings`), wrapped into
    ``folder/<name>.xml``. The rings run ``settings.nproc`` at a time, each as one process
    (the same matrices for any ``nproc``)."""
    t0 = time.perf_counter()
    ring, _ = klems_patch_rings()
    flux = {key: np.zeros((ring.size, ring.size)) for key in KEYS}
    single = replace(settings, nproc=1)
    with ThreadPoolExecutor(max_workers=max(1, min(settings.nproc, len(ring_folders)))) as pool:
        list(pool.map(lambda sub: flux_passes(sub, single), ring_folders))
    for k, sub in enumerate(ring_folders):
        cols = ring == k
        for key in KEYS:
            m = np.loadtxt(sub / f"{key}.dat", ndmin=2)
            if m.shape != flux[key].shape:
                raise EngineError(f"{sub / key}.dat: {m.shape} values, expected 145 × 145",
                                  command=["rfluxmtx"], stderr="")
            flux[key][:, cols] = m[:, cols]
    xml = wrap_flux(folder, reciprocal_rings(flux), name, thickness, width, height, comment)
    return BsdfRun(xml, check_bsdf(xml), time.perf_counter() - t0)


def wrap_flux(folder: Path, flux: dict[str, np.ndarray], name: str, thickness: float,
              width: float, height: float, comment: str = "") -> Path:
    """The four flux matrices F[out, in] (``tf rf tb rb``) made reciprocal patch by patch
    (:func:`reciprocal_patches`), written to ``folder/*.dat`` and wrapped
    (:func:`wrap_klems`) into ``folder/<name>.xml``."""
    folder.mkdir(parents=True, exist_ok=True)
    flux = reciprocal_patches(flux)
    for key in KEYS:
        np.savetxt(folder / f"{key}.dat", flux[key], fmt="%.7e", delimiter="\t")
    return wrap_klems(folder, name, thickness, width, height, comment)


def check_bsdf(xml: Path) -> str:
    """checkBSDF's report of ``xml``; an XML it rejects raises :class:`EngineError`."""
    text = run(["checkBSDF", str(xml)]).decode(errors="replace")
    if "Component" not in text:
        raise EngineError(f"checkBSDF rejected {xml}", command=["checkBSDF", str(xml)],
                          stderr=text)
    return text


def tensor_tree_bsdf(folder: Path, settings: FluxSettings, name: str, thickness: float,
                     width: float, height: float) -> Path:
    """A rank-4 tensor tree (genBSDF ``-t4``) beside the Klems XML: rfluxmtx over
    Shirley–Chiu square bins ``h=±sc<2^N>``, rttree_reduce, wrapBSDF ``-a t4``."""
    ns = 2 ** settings.tensor_tree
    write_text(folder / "tt_receivers.rad", receivers_text(f"sc{ns}").replace(
        "o=face.dat", "o=tt_face.dat").replace("o=behind.dat", "o=tt_behind.dat"))
    write_text(folder / "tt_fsender.rad", sender_text(True, width, height, -thickness - EPS,
                                                      f"sc{ns}"))
    write_text(folder / "tt_bsender.rad", sender_text(False, width, height, EPS, f"sc{ns}"))
    parts: list[str] = []
    omega = f"Omega:PI/({ns}*{ns})"
    for sender, (trans, refl, tkey, rkey) in (
            ("tt_fsender.rad", ("tt_face.dat", "tt_behind.dat", "tf", "rf")),
            ("tt_bsender.rad", ("tt_behind.dat", "tt_face.dat", "tb", "rb"))):
        run(["rfluxmtx", *settings.options(), "-h", "-ff", sender, "tt_receivers.rad", "-i",
             "system.oct"], cwd=folder)
        for src, key, avg in ((trans, tkey, []), (refl, rkey, ["-a"])):
            y = run(["rcalc", "-if3", "-e", omega, "-e", "Ri=$1;Gi=$2;Bi=$3",
                     "-e", f"Yi={Y_WEIGHTS[0]}*Ri+{Y_WEIGHTS[1]}*Gi+{Y_WEIGHTS[2]}*Bi",
                     "-e", "$1=Yi/Omega", "-of", src], cwd=folder)
            tree = run(["rttree_reduce", *avg, "-h", "-ff", "-t", "90", "-r", "4", "-g",
                        str(settings.tensor_tree)], stdin=y, cwd=folder)
            (folder / f"tt_{key}.dat").write_bytes(tree)
            parts += [f"-{key}", f"tt_{key}.dat"]
    fields = f"t={thickness:.6g};w={width:.6g};h={height:.6g};n={name};m=radtree"
    xml = folder / f"{name}_t4.xml"
    run(["wrapBSDF", "-a", "t4", "-u", "meter", "-f", fields, *parts], cwd=folder,
        stdout_path=xml)
    check_bsdf(xml)
    return xml
