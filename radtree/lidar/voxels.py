"""Plant area density of one tree on a voxel grid, from its points (Beer–Lambert inversion).

Beams are taken as vertical, from above (airborne scanning near nadir). In each column of
``size_m`` × ``size_m`` the returns are counted per layer of ``size_m``; of the N(z) returns at
or below height z, the share that also lies below the layer's bottom is the layer's gap
fraction, and Beer–Lambert's law inverts it (MacArthur & Horn 1969, Ecology 50:802–804; the
voxel form of e.g. Béland et al. 2019, Agric. For. Meteorol. 276:107627):

    PAD = −ln( (N(z_bottom) + ½) / (N(z_top) + ½) ) / (G · Δz)   (m² of plant area per m³)

with G the mean projection of the plant elements on the horizontal (for vertical beams
G = E|cos θ_L|: cos α for one inclination α; from the species' leaf angle distribution or
the crown's slats, given by the caller). Ground returns (heights below ``ground_m``) count as
beams that crossed the whole column. The ½ added to both counts is the classic correction of
the log of a binomial proportion (Haldane 1955, Ann. Hum. Genet. 20:309–311; Anscombe 1956,
Biometrika 43:461–464; Gart & Zweifel 1967, Biometrika 54:181–187): the plain −ln(1 − I/N) of
I intercepted among N beams is biased by O(1/N), and the former "N(z_bottom) = ½ when no beam
left" made it worse. Expected estimate / truth for a voxel of optical depth τ = 0.53 (the
Mendoza crown's 1.25 m voxels): plain with that rule 0.54, 1.08, 1.18, 1.16, 1.08, 1.02 for
N = 1, 2, 3, 5, 10, 30 beams; with ½ added 0.85, 0.98, 1.00, 1.01, 1.00, 1.00 (τ = 0.1: 0.66,
1.32, 1.23, 1.13, 1.06, 1.02 against 1.05, 1.03, 1.01, 1.00, 1.00, 1.00) — the bottom of a
dense crown, reached by one or two beams a column, and the top of a sparse one, entered by
many but hit by few, were both off. A voxel no beam reached (N(z_top) = 0) is occluded: when
a voxel above it in its column holds plant area and it is not below the tree's lowest
vegetation return, it takes the mean density of the reached voxels of its layer in the crown's
columns (:func:`fill_occluded`; such voxels, searched by no pulse, are a class of their own in
e.g. "Near-complete sampling of forest structure from high-density drone lidar demonstrated
by ray tracing", Remote Sens. 2024, 16:2774 — filling them with their layer's mean is the
choice made here); elsewhere PAD 0. Clumping inside a voxel is not
modelled (random elements in each voxel).

Points classed as buildings or noise (:data:`radtree.lidar.ground.NOT_TREES`) are left out.

Wood: the points do not tell leaves from branches, so the density is *plant* area (leaves +
wood, Chen & Black's "plant area index" sense): a leaf-on crown's wood counts as leaf area.
Scans of leafless crowns give the wood alone.

Voxel size: by default 5 × the mean point spacing s of the first returns (:meth:`Tile.spacing_m`,
rounded up to 5 cm), so a column holds about 25 beams; finer than 3·s (fewer than ~9 beams a
column, when one beam more or less moves a layer's gap by more than 10 %) is refused. Terrestrial
scans (beams from a scanner on the ground) break the vertical-beam assumption, and so do
airborne beams off nadir where overlapping strips cross (the synthetic street of
``benchmarks/lidar_roundtrip.py``: leaf area within 10 % for 7/20 trees as columns, 18/20
along the beams): when the caller knows where each beam was fired (``origins``), the beams are
followed along their own paths instead (:mod:`radtree.lidar.beams`, the same Beer–Lambert law
per voxel, exactly this inversion for vertical beams).

Along the beams two more rules hold by default (``envelope``, ``pulse_min``; the columns keep
the rules above). The beams are clipped to the crown envelope, the convex hull of the tree's
vegetation returns pushed out by one point spacing (:mod:`radtree.lidar.envelope`): a rim
voxel's density is that of its part inside the envelope, its plant area that density times
that part's volume (the rim voxels were 9–15 % low, the trees −2.8 % on average). A voxel inside
the envelope that fewer than ``pulse_min`` = 5 beams entered (AMAPVox's ``plantAreaDensity``
leaves such voxels without an estimate by default, ``pulse.min = 5``; Pimont, Allard, Soma &
Dupuy 2018, "Estimators and confidence intervals for plant area density at voxel scale with
T-LiDAR", Remote Sens. Environ. 215:343–370, find their estimators consistent from about 5
beams) has no estimate of its own (at the occluded base of the street's S04, scanner seed 1,
1.2 m voxels, a voxel entered by 2 beams, both intercepted, gave −ln(0.5/2.5) / (G·l̄) =
1.55 m²/m³, 2.7 m² of a 50 m² crown). The undersampled voxels of a layer are inverted
together (``pool``, the default): their entering and intercepted beams and optical paths are
summed and the same Beer–Lambert estimate taken over them as one volume, the density every
one of them gets (a region of one density is inverted from all the beams through it, as a
voxel is; the support grows where the beams are too few, not the estimator); a layer whose undersampled voxels together saw fewer
than 5 beams takes the mean of its voxels entered by at least 5, and a layer with neither the
value of the nearest layer above. This replaces the occluded-voxel fill there (a voxel no
beam entered is one of those under 5). Before (each undersampled voxel the mean of its
layer's voxels entered by at least 5, ``pool=False``): under a dense crown (one like the
façade crown of ``benchmarks/lidar_facade.py``: radius 5 m, vertical semi-axis 4.75 m, base
3 m, 4 crossings, 241 m², scanned alone by the default scanner) the lowest layers are almost all
undersampled and their few sampled voxels are rim voxels reached from the side, so the layer
took the mean of 1–3 of them, or 0 when none (scans 1–4 at 20 pulses/m²: leaf area +11.4,
+5.3, −5.3, −2.4 %; the crown's lowest 2.4 m 82.7, 65.1, 40.4, 53.9 m² for 51.1). Pooled:
−3.7, −5.8, −5.0, −3.4 %; 50.2, 41.8, 47.9, 53.9 m² (``tests/test_lidar_beams.py``; one thin
ray a pulse).

Several returns a pulse (``echo_weight``, :func:`echo_weights`): each return is a sub-beam
from the pulse's origin to it, weighted by its intensity's share of the pulse's returns
(``"intensity"``, the default: the part of the footprint it intercepted, when every surface
reflects alike) or by 1/(number of returns) (``"equal"``); :mod:`radtree.lidar.beams`. A
file of single returns gives every beam weight 1 either way. Real intensities also carry
each surface's reflectance (leaves against asphalt or soil), which the shares then mix in;
not corrected here. "Beams" in the 5-beam minimum are effective beams, (Σ w)² / Σ w²
(:meth:`radtree.lidar.beams.BeamCounts.effective`). On the synthetic street's default scan
(16 sub-rays a pulse over the 0.15 m footprint, up to 4 returns) the crown base is entered by
many partial pulses and seldom undersampled.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from radtree.errors import ConfigError
from radtree.lidar.beams import BeamCounts, effective_beams
from radtree.lidar.envelope import Envelope, fill_undersampled
from radtree.lidar.ground import NOT_TREES, heights_above_ground
from radtree.lidar.tile import Tile, read_tile

#: default voxel size in point spacings; finer than MIN_SPACINGS is refused (module text)
DEFAULT_SPACINGS = 5.0
MIN_SPACINGS = 3.0
#: beams a voxel needs for its own estimate along the beams; fewer: its layer's mean (module
#: text; AMAPVox's ``plantAreaDensity`` default ``pulse.min = 5``)
PULSE_MIN = 5.0


@dataclass(frozen=True)
class VoxelGrid:
    """Plant area density ``pad`` [i, j, k] (m²/m³) of cells ``size_m`` wide; cell (i, j, k)
    spans x0 + i·size …, y0 + j·size …, and heights k·size … above ground (x east, y north,
    z up, m). ``g`` is the projection used in the inversion."""

    x0: float
    y0: float
    size_m: float
    pad: np.ndarray
    g: float
    spacing_m: float
    returns: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # x, y, height

    def returns_in(self, i: np.ndarray, j: np.ndarray, k: np.ndarray,
                   rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """For voxels (i, j, k): the x, y of one of their returns drawn at random, and
        whether the voxel has any (where not, x, y are NaN)."""
        r = self.returns
        ri = np.floor((r[:, 0] - self.x0) / self.size_m).astype(np.int64)
        rj = np.floor((r[:, 1] - self.y0) / self.size_m).astype(np.int64)
        rk = np.floor(r[:, 2] / self.size_m).astype(np.int64)
        shape = self.pad.shape
        ok = (ri >= 0) & (ri < shape[0]) & (rj >= 0) & (rj < shape[1]) & (rk >= 0) & (
            rk < shape[2])
        lin = np.ravel_multi_index((ri[ok], rj[ok], rk[ok]), shape)
        order = np.argsort(lin, kind="stable")
        lin_sorted, xy = lin[order], r[ok][order, :2]
        want = np.ravel_multi_index((i, j, k), shape)
        start = np.searchsorted(lin_sorted, want, side="left")
        count = np.searchsorted(lin_sorted, want, side="right") - start
        pick = start + np.floor(rng.random(len(want)) * count).astype(np.int64)
        has = count > 0
        out = np.full((len(want), 2), np.nan)
        out[has] = xy[pick[has]]
        return out, has

    @property
    def leaf_area_m2(self) -> float:
        """Total (one-sided) plant area, m²."""
        return float(self.pad.sum() * self.size_m**3)

    def profile(self) -> tuple[np.ndarray, np.ndarray]:
        """(layer bottoms m, plant area of each layer m²) — the vertical profile."""
        per = self.pad.sum(axis=(0, 1)) * self.size_m**3
        return np.arange(len(per)) * self.size_m, per

    def centroid_xy(self) -> np.ndarray:
        """The plant-area-weighted horizontal centroid (m)."""
        w = self.pad.sum(axis=2)
        i, j = np.nonzero(w)
        ww = w[i, j]
        return np.array([self.x0 + (np.average(i, weights=ww) + 0.5) * self.size_m,
                         self.y0 + (np.average(j, weights=ww) + 0.5) * self.size_m])


def default_voxel_m(spacing_m: float) -> float:
    """5 point spacings, rounded up to 5 cm (module text)."""
    return math.ceil(DEFAULT_SPACINGS * spacing_m / 0.05 - 1e-9) * 0.05


def plant_area_density(xy: np.ndarray, heights: np.ndarray, size_m: float, g: float,
                       ground_m: float = 0.5) -> tuple[float, float, np.ndarray]:
    """(x0, y0, pad[i, j, k]) by the column inversion of the module text."""
    x0, y0, pad, _ = _columns(xy, heights, size_m=size_m, g=g, ground_m=ground_m)
    return x0, y0, pad


def fill_occluded(pad: np.ndarray, entering: np.ndarray, *, lowest_k: int
                  ) -> tuple[np.ndarray, int]:
    """(pad, voxels filled): voxels no beam reached (``entering`` 0) in a crown column (one
    with plant area), under a voxel with plant area and not below layer ``lowest_k`` (the
    lowest vegetation return's) take the mean density of the reached voxels of their layer
    in crown columns (module text)."""
    crown_col = pad.sum(axis=2) > 0
    above: np.ndarray = np.cumsum((pad > 0)[..., ::-1], axis=2)[..., ::-1] - (pad > 0)   # dense voxels above
    k = np.arange(pad.shape[2])[None, None, :]
    occluded = (entering <= 0) & crown_col[..., None] & (above > 0) & (k >= lowest_k)
    reached = (entering > 0) & crown_col[..., None] & (k >= lowest_k)
    with np.errstate(invalid="ignore"):
        layer = np.nan_to_num(np.sum(pad * reached, axis=(0, 1)) / np.sum(reached, axis=(0, 1)))
    out = np.where(occluded, layer[None, None, :], pad)
    return out, int(occluded.sum())


def _columns(xy: np.ndarray, heights: np.ndarray, *, size_m: float, g: float,
             ground_m: float, weight: np.ndarray | None = None
             ) -> tuple[float, float, np.ndarray, np.ndarray]:
    """(x0, y0, pad, beams reaching each voxel N(z_top)) of the column inversion; each return
    counted with its ``weight`` (:func:`echo_weights`; 1 when None), the ½ added in effective
    beams (Σ w)² / Σ w² (:func:`radtree.lidar.beams.effective_beams`)."""
    x0, y0 = (np.floor(xy.min(axis=0) / size_m) * size_m).tolist()
    ij = np.floor((xy - [x0, y0]) / size_m).astype(np.int64)
    nx, ny = (ij.max(axis=0) + 1).tolist()
    veg = heights >= ground_m
    nz = max(1, int(math.ceil(heights[veg].max() / size_m))) if veg.any() else 1
    k = np.where(veg, np.floor(heights / size_m).astype(np.int64), -1)
    k = np.clip(k, -1, nz - 1)
    w = np.ones(len(heights)) if weight is None else np.asarray(weight, float)
    counts = np.zeros((nx, ny, nz + 1))   # [..., 0] = ground, [..., k + 1] = layer k
    np.add.at(counts, (ij[:, 0], ij[:, 1], k + 1), w)
    squares = np.zeros((nx, ny, nz + 1))
    np.add.at(squares, (ij[:, 0], ij[:, 1], k + 1), w * w)
    below_top = np.cumsum(counts, axis=2)[..., 1:]        # N(z_top of layer k)
    below_bottom = below_top - counts[..., 1:]            # N(z_bottom of layer k)
    n_eff = effective_beams(below_top, np.cumsum(squares, axis=2)[..., 1:])
    with np.errstate(divide="ignore", invalid="ignore"):
        gap = (n_eff * below_bottom / below_top + 0.5) / (n_eff + 0.5)   # ½ added
        pad = np.where(below_top > 0, -np.log(np.minimum(gap, 1.0)) / (g * size_m), 0.0)
    return float(x0), float(y0), pad, below_top


def echo_weights(tile: Tile, rule: str = "equal") -> np.ndarray:
    """Each return's share of its pulse (module text): ``"equal"`` 1 / number of returns;
    ``"intensity"`` its intensity over the summed intensity of its pulse's returns in the
    tile (a pulse: one flight line or scan position and one GPS time; a return of the pulse
    clipped out of the file is not counted), falling back to 1 / number of returns for a
    pulse whose returns carry no intensity (all 0) or that cannot be told apart (more points
    share its line and time than its number of returns: a file without GPS times)."""
    equal = 1.0 / np.maximum(tile.number_of_returns, 1).astype(float)
    if rule == "equal" or tile.intensity is None or tile.gps_time is None:
        return equal
    if rule != "intensity":
        raise ValueError(f"echo weight {rule!r}: 'equal' or 'intensity'")
    sid = np.zeros(len(tile)) if tile.source_id is None else tile.source_id
    _, pulse = np.unique(np.column_stack([sid, tile.gps_time]), axis=0, return_inverse=True)
    pulse = pulse.ravel()
    inten = np.asarray(tile.intensity, float)
    total = np.bincount(pulse, weights=inten)[pulse]
    # a "pulse" holding more returns than its number of returns is no pulse (no GPS times)
    one_pulse = np.bincount(pulse)[pulse] <= np.maximum(tile.number_of_returns, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((total > 0) & one_pulse, inten / total, equal)


def _beam_pad(tile: Tile, *, heights: np.ndarray, origin: np.ndarray, size: float,
              g_of_mu: Callable[[np.ndarray], np.ndarray], ground_m: float = 0.5,
              empty: tuple[np.ndarray, np.ndarray] | None = None,
              envelope_m: float | None = None, echo_weight: str = "equal"
              ) -> tuple[float, float, np.ndarray, BeamCounts, np.ndarray | None]:
    """(x0, y0, pad, entering beams, envelope fractions) by following every point's beam
    (:mod:`radtree.lidar.beams`) on the grid over the points' extent, heights 0 … the highest
    point; shots without a return (``empty``: origins, directions) run 1 km on, shifted by the
    median terrain. With ``envelope_m`` (the margin, m) the beams are clipped to the crown
    envelope (:mod:`radtree.lidar.envelope`): pad is then the density of each voxel's part
    inside it and the fractions (share of each voxel inside) are returned, else None."""
    from radtree.lidar.beams import Beams, beam_counts, density

    xy = tile.xyz[:, :2]
    x0, y0 = (np.floor(xy.min(axis=0) / size) * size).tolist()
    nx, ny = (np.floor((xy - [x0, y0]) / size).astype(np.int64).max(axis=0) + 1).tolist()
    nz = max(1, int(math.ceil(heights.max() / size)))
    end = np.column_stack([xy, heights])
    start = np.asarray(origin, float) - np.column_stack(
        [np.zeros((len(xy), 2)), tile.xyz[:, 2] - heights])   # terrain under the return
    weight = echo_weights(tile, echo_weight)
    hit = heights >= ground_m
    if empty is not None and len(empty[0]):
        shift = np.array([0.0, 0.0, float(np.median(tile.xyz[:, 2] - heights))])
        eo = np.asarray(empty[0], float) - shift
        start = np.vstack([start, eo])
        end = np.vstack([end, eo + 1000.0 * np.asarray(empty[1], float)])
        hit = np.r_[hit, np.zeros(len(eo), bool)]
        weight = np.r_[weight, np.ones(len(eo))]
    lo, shape = np.array([x0, y0, 0.0]), (int(nx), int(ny), nz)
    env = None if envelope_m is None else Envelope.of(end[hit], envelope_m)
    beyond_max = None
    if env is not None:
        start, end, hit, weight, beyond_max = _clip_beams(env, start, end, hit, weight)
    counts = beam_counts(Beams(start, end, hit, weight), lo=lo, size=size, shape=shape,
                         g_of_mu=g_of_mu, beyond_max=beyond_max)
    pad = density(counts.entering, counts.hits, counts.optical, counts.effective())
    frac = None if env is None else env.fractions(lo, size, shape)
    return float(x0), float(y0), pad, counts, frac


def _clip_beams(env: Envelope, start: np.ndarray, end: np.ndarray, hit: np.ndarray,
                weight: np.ndarray) -> tuple[np.ndarray, ...]:
    """The beams' parts inside the envelope: (start, end, hit, weight, how far each may run
    on past its return inside the envelope m); beams that miss it are dropped."""
    t_in, t_out = env.clip(start, end)
    d = end - start
    keep = (t_in < np.minimum(t_out, 1.0)) | hit     # a return lies inside (margin > 0)
    s2 = start + np.where(hit, np.minimum(t_in, 1.0), t_in)[:, None] * d
    e2 = start + np.where(hit, 1.0, np.minimum(t_out, 1.0))[:, None] * d
    beyond = np.maximum(t_out - 1.0, 0.0) * np.linalg.norm(d, axis=1)
    return s2[keep], e2[keep], hit[keep], weight[keep], beyond[keep]


def tree_voxels(path: str | Path, g: float, size_m: float | None = None,
                ground: str = "class", field: str = "tree.points_voxel_m", *,
                origins: Callable[[Tile], np.ndarray] | None = None,
                g_of_mu: Callable[[np.ndarray], np.ndarray] | None = None,
                empty: Callable[[Tile], tuple[np.ndarray, np.ndarray]] | None = None,
                fill: bool = True, envelope: bool = True,
                pulse_min: float = PULSE_MIN, pool: bool = True,
                echo_weight: str = "intensity") -> VoxelGrid:
    """The plant area density grid of the one tree in ``path`` (module text); ConfigError
    naming the file and the fix for an empty or one-point tree, no ground, a voxel finer
    than the point spacing supports. With ``origins`` (where each point's beam was fired,
    (n, 3) in the tile's coordinates, e.g. :meth:`radtree.lidar.scanner.AlsScan.origins`)
    the beams are followed along their own paths (:mod:`radtree.lidar.beams`, G from
    ``g_of_mu``, else ``g`` for every direction) instead of taken as vertical; ``empty`` gives
    the (origins, unit directions) of the shots that returned nothing (a terrestrial scan's
    sky shots, :meth:`radtree.lidar.tls.TlsScan.empty_shots`), followed out of the grid."""
    tile: Tile = read_tile(path)
    if not 0.0 < g <= 1.0:
        raise ConfigError(f"projection G = {g:g}, expected 0 < G ≤ 1", source=tile.source)
    heights, _ = heights_above_ground(tile, ground)
    keep = ~np.isin(tile.classification, NOT_TREES)   # roofs, noise: no beam of the crown
    tile, heights = tile.subset(keep), heights[keep]
    veg = heights >= 0.5
    if veg.sum() < 2:
        raise ConfigError(f"the tree has {int(veg.sum())} point(s) 0.5 m or more above "
                          "ground: no crown to fill; clip a tree with its points (radtree "
                          "lidar clip TILE --tree ID --out tree.laz)", source=tile.source)
    spacing = tile.spacing_m()
    size = default_voxel_m(spacing) if size_m is None else float(size_m)
    if size < MIN_SPACINGS * spacing:
        raise ConfigError(f"voxel size {size:g} m is finer than this scan supports: its mean "
                          f"point spacing is {spacing:.2f} m, so a column of {size:g} m holds "
                          f"≈ {(size / spacing) ** 2:.0f} beams; use at least "
                          f"{MIN_SPACINGS * spacing:.2f} m, or leave {field} unset for the "
                          f"default {default_voxel_m(spacing):g} m", source=tile.source,
                          field=field)
    frac = None
    if origins is None:
        x0, y0, pad, entering = _columns(tile.xyz[:, :2], heights, size_m=size, g=g,
                                         ground_m=0.5, weight=echo_weights(tile, echo_weight))
    else:
        x0, y0, pad, counts, frac = _beam_pad(
            tile, heights=heights, origin=origins(tile), size=size,
            g_of_mu=g_of_mu or (lambda mu: np.full(np.shape(mu), g)),
            empty=None if empty is None else empty(tile),
            envelope_m=spacing if envelope else None, echo_weight=echo_weight)
        entering = counts.effective()
    lowest_k = int(np.floor(heights[veg].min() / size))
    if frac is not None:
        if fill:
            pad, _ = fill_undersampled(pad, entering, inside=frac > 0,
                                       lowest_k=lowest_k, pulse_min=pulse_min,
                                       counts=counts if pool else None)
        pad = pad * frac
    elif fill:
        pad, _ = fill_occluded(pad, entering, lowest_k=lowest_k)
    returns = np.column_stack([tile.xyz[veg, :2], heights[veg]])
    return VoxelGrid(x0, y0, size, pad, g, spacing, returns)
