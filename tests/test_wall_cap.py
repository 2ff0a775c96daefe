"""The wall cap's BSDF seen from the sensors (:mod:`radtree.pipeline.wall_cap`): the crown
depth per Klems patch left to the cap, the depth-node mixing, the cap cut into cells, and the
XML (checkBSDF, reciprocity, energy, darker where the sensors look up into the crown)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.pipeline.wall_cap import (
    cap_frame,
    depth_nodes,
    klems_directions,
    mixed,
    patch_depths,
)
from radtree.trees.envelope import CrownRowSpec
from tests.conftest import ROOT, needs_radiance

OFFICE = ROOT / "examples" / "office-block"


def sphere_row(r: float = 4.0, centre_n: float = 3.0, centre_z: float = 7.0) -> CrownRowSpec:
    return CrownRowSpec(centres=np.array([[0.0, centre_n, centre_z]]), a=r, b=r, n_clip=0.015,
                        strips=np.array([[-np.inf, np.inf]]), trunk_radius=0.2, trunk_top=5.0)


def travel_directions(sign: float) -> np.ndarray:
    theta, phi = klems_directions()
    x, y, z = cap_frame()
    return ((sign * np.sin(theta) * np.cos(phi))[:, None] * x
            + (sign * np.sin(theta) * np.sin(phi))[:, None] * y + np.cos(theta)[:, None] * z)


@pytest.mark.parametrize("point_z", [7.0, 4.5])
def test_patch_depths_are_the_chord_left_by_the_far_facet(point_z):
    """A sphere of radius R: a line from S along u runs (C − S)·u + R cos θ_P inside, so the
    cap carries b = (C − S)·u — h cos ψ at the foot point (the ring samples before), more
    upwards and less downwards from a point below the centre (the office's window)."""
    spec, r = sphere_row(), 4.0
    s = np.array([0.0, spec.n_clip, point_z])
    floor = 0.3
    front, back = patch_depths(spec, s, r, floor, level=4)
    c = spec.centres[0]
    for b, sign in ((front, 1.0), (back, -1.0)):
        exact = travel_directions(sign) @ (c - s)
        deep = exact > floor + 0.1
        assert deep.sum() > 60
        err = np.abs(b[deep] - exact[deep])            # polyhedral hull vs the sphere
        # (grazing lines leave near the cap's rim, where the hull's facets are coarsest)
        assert np.percentile(err, 90) < 0.1 and err.mean() < 0.04, (err.max(), err.mean())
        assert np.all(b >= floor)
    theta, phi = klems_directions()
    source_up = np.sin(theta) * np.sin(phi) < -0.5   # back: the source is −(travel)
    source_down = np.sin(theta) * np.sin(phi) > 0.5
    if point_z == 7.0:                              # the foot point: symmetric
        assert back[source_up].mean() == pytest.approx(back[source_down].mean(), rel=0.05)
    else:
        assert back[source_up].mean() > 1.5 * back[source_down].mean()


def test_depth_nodes_span_the_depths_in_small_steps():
    taus = np.array([0.05, 0.3, 2.0, 4.4])
    nodes = depth_nodes(taus)
    assert nodes[0] == pytest.approx(0.05) and nodes[-1] == pytest.approx(4.4)
    assert np.all(nodes[1:] / nodes[:-1] <= 1.5 + 1e-9)


def test_mixed_columns_follow_an_exponential_depth_law():
    """Node matrices of a layer whose transmission falls as exp(−κ τ) with a fixed shape:
    a column at any depth between (or beyond) the nodes gets exp(−κ τ) times that shape."""
    kappa, nodes = 0.8, np.array([0.5, 1.0, 2.0])
    rng = np.random.default_rng(3)
    shape = rng.random((145, 145))
    shape /= shape.sum(axis=0)
    mats = [shape * math.exp(-kappa * t) for t in nodes]
    taus = rng.uniform(0.5, 3.0, 145)              # beyond 2.0: extrapolated
    got = mixed(mats, nodes, taus, transmission=True)
    want = shape * np.exp(-kappa * taus)[None, :]
    assert got.sum(axis=0) == pytest.approx(want.sum(axis=0), rel=1e-9)
    np.testing.assert_allclose(got, want, rtol=1e-9)
    refl = mixed(mats, nodes, np.full(145, 1.0), transmission=False)
    np.testing.assert_allclose(refl, mats[1])      # at a node: that node's column


def test_cap_cells_keep_the_area_and_stay_in_their_cells():
    from radtree.trees.bsdf_shell import cap_cells

    tri = np.array([[[-3.1, 0.015, 4.0], [2.7, 0.015, 4.2], [0.3, 0.015, 11.4]]])
    cells = cap_cells(tri, 0.5)

    def area(t: np.ndarray) -> float:
        return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]),
                                          axis=1).sum())

    assert area(cells) == pytest.approx(area(tri), rel=1e-9)
    assert len(cells) > 50
    for axis in (0, 2):
        lo = np.floor(cells[:, :, axis].min(axis=1) / 0.5 + 1e-9)
        hi = np.ceil(cells[:, :, axis].max(axis=1) / 0.5 - 1e-9)
        assert np.all(hi - lo <= 1)                 # no triangle across a grid line
    n0 = np.cross(tri[0, 1] - tri[0, 0], tri[0, 2] - tri[0, 0])
    n = np.cross(cells[:, 1] - cells[:, 0], cells[:, 2] - cells[:, 0])
    assert np.all(n @ n0 > 0)                       # winding kept


@needs_radiance
def test_wall_cap_xml_is_reciprocal_passive_and_darker_looking_up(tmp_path):
    """The office's wall cap seen from its sensors (below the crown centre, the row running
    along the wall): checkBSDF accepts it, ring exchanges reciprocal, T + R ≤ 1, and light
    arriving from above (through more crown) is transmitted less than light from below."""
    from radtree.bsdf.klems import read_klems
    from radtree.config import load_project
    from radtree.engines.radiance.bsdf import FluxSettings
    from radtree.pipeline.crown_bsdf import CHORD_MIN_SLATS, ensure_bsdf, slab_depth
    from radtree.pipeline.wall_cap import PatchDepthSample, wall_cap_sample

    proj = load_project(OFFICE)
    tree = proj.tree
    sample = wall_cap_sample(proj, proj.scenario("with"), tree, slab_depth(tree),
                             CHORD_MIN_SLATS * tree.louvers.slat_size_m)
    assert isinstance(sample, PatchDepthSample) and 8 <= len(sample.rings) <= 16
    assert sample.info["b_max_m"] > 2 * sample.thickness   # sideways along the row
    settings = FluxSettings(samples=16, ab=2, ad=2, lw=1e-3, tiles=3, nproc=2)
    k = read_klems(ensure_bsdf(sample, settings, tmp_path / "cap", "cap").xml)
    assert max(k.reciprocity_error().values()) < 1e-3
    assert max(k.energy_excess().values()) <= 1e-3
    theta, phi = klems_directions()
    tb = k.hemispherical("tb")
    up = (np.sin(theta) * np.sin(phi) < -0.5)      # back incidence: source = −travel
    down = (np.sin(theta) * np.sin(phi) > 0.5)
    assert tb[up].mean() < 0.5 * tb[down].mean()
