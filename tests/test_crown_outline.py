"""Crowns following their outlines (issue 41 item 1): the radial function of an outline, slats
of L- and ellipse-shaped crowns inside them with the leaf area of density × volume, round
outlines giving today's crown, and inventory outlines read and projected like the positions."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from radtree.config import Louvers, load_project
from radtree.errors import ConfigError
from radtree.trees.district import single_spec
from radtree.trees.louvers_free import build_free_louvers
from radtree.trees.outline import CrownOutline, contains, ring_area
from radtree.trees.volume import build_volume_louvers, volume_density
from tests.test_district import district, point

#: an L: a 6 m × 2.5 m arm east and a 2.5 m × 3.5 m arm north, the trunk in the corner
L_RING = np.array([[-1, -1], [5, -1], [5, 1.5], [1.5, 1.5], [1.5, 5], [-1, 5]], float)
THETA = np.linspace(0.0, 2.0 * math.pi, 96, endpoint=False)
#: an ellipse of semi-axes 4 m (east) and 2 m (north) about (1, 0), the trunk at the origin
ELLIPSE = np.column_stack([1.0 + 4.0 * np.cos(THETA), 2.0 * np.sin(THETA)])


def _spec(ring: np.ndarray, b: float = 3.0):
    out = CrownOutline.of(ring, centre=np.zeros(2))
    return replace(single_spec(np.array([0.0, 0.0, 3.0 + b]), 3.0, b, 0.15, 3.0 + 0.5 * b),
                   outline=out)


def test_radial_function_area_and_roundness() -> None:
    """r(θ) of the L from its corner: 5 m east, 5 m north, √2 to the corner (−1, −1), and
    1.5·√2 to the inner corner (1.5, 1.5); the body's plan area is the polygon's (the L is
    star-shaped from the trunk)."""
    out = CrownOutline.of(L_RING, centre=np.zeros(2))
    r = out.reach(np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0], [1.0, 1.0]]))
    np.testing.assert_allclose(r, [5.0, 5.0, math.sqrt(2.0), 1.5 * math.sqrt(2.0)], rtol=1e-9)
    assert out.area_m2 == pytest.approx(ring_area(L_RING), rel=1e-5)   # 23.75 m²
    assert ring_area(L_RING) == pytest.approx(23.75)
    assert out.extent_towards(np.array([0.0, -1.0])) == pytest.approx(1.0)
    assert not out.is_round(3.0)
    circle = 2.5 * np.column_stack([np.cos(THETA), np.sin(THETA)])
    assert CrownOutline.of(circle, centre=np.zeros(2)).is_round(2.5)          # 96-gon: 0.05 % off
    assert not CrownOutline.of(circle * [1.1, 1.0], centre=np.zeros(2)).is_round(2.5)


@pytest.mark.parametrize("ring", [L_RING, ELLIPSE], ids=["L", "ellipse"])
def test_volume_slats_inside_outline_with_density_times_volume(ring: np.ndarray) -> None:
    """Volume louvers in an outline crown: every slat centre inside the outline, round(ρ·V)
    slats drawn with V = 4/3·b·A (A the polygon's area: leaf area = density × volume), the
    Monte Carlo volume of the body within 3 s.e. of 4/3·b·A, and the centres uniform in the
    body (their share east of x = 1.5 m as the body's, within 3 binomial s.e.)."""
    spec = _spec(ring)
    lv = Louvers(arrangement="volume", crossings=6, slat_size_m=0.3)
    polys, info = build_volume_louvers(spec, lv)
    centres = np.array([p.mean(axis=0) for p in polys])
    assert contains(ring, x=centres[:, 0], y=centres[:, 1]).all()
    volume = 4.0 / 3.0 * spec.b * ring_area(ring)
    assert info["slats_drawn"] == round(volume_density(lv, spec.b) * volume)
    assert info["crown_volume_m3"] == pytest.approx(volume, abs=3 * info["crown_volume_se_m3"])
    assert (centres[:, 2] >= 3.0).all() and (centres[:, 2] <= 9.0).all()
    rng = np.random.default_rng(5)
    box = rng.uniform([-4, -4, 3], [6, 6, 9], (400_000, 3))
    body = box[spec.inside(box)]
    share = float(np.mean(body[:, 0] > 1.5))
    got = float(np.mean(centres[:, 0] > 1.5))
    assert got == pytest.approx(share, abs=3 * math.sqrt(share * (1 - share) / len(centres)))


def test_layered_slats_inside_outline() -> None:
    """Layered louvers: every slat corner inside the L (the layers' lenses scaled into it)."""
    polys, _ = build_free_louvers(_spec(L_RING), Louvers(arrangement="layers", layers=4,
                                                          slat_size_m=0.3))
    corners = np.vstack(polys)
    assert len(polys) > 300
    assert contains(L_RING, x=corners[:, 0], y=corners[:, 1]).all()


def _leaves(p):
    from radtree.pipeline.assemble import make_scene

    scene = make_scene(p, p.scenario("T")).scene
    return scene, {m.name: m for m in scene.meshes if m.material.startswith("leaf")}


def _ring(xy: np.ndarray) -> list[list[float]]:
    return [[float(x), float(y)] for x, y in np.vstack([xy, xy[:1]])]


def test_round_outlines_give_todays_crowns(tmp_path: Path) -> None:
    """Two trees of one species with round outlines (96-gons of the crown radius about the
    trunk): the same scene as without outlines — one shared crown, two instances, same
    triangles."""
    circle = 2.5 * np.column_stack([np.cos(THETA), np.sin(THETA)])
    plain = [point("T1", -6.0, 4.0), point("T2", 6.0, 4.0)]
    shaped = [point("T1", -6.0, 4.0, crown_outline=_ring(circle + [-6.0, 4.0])),
              point("T2", 6.0, 4.0, crown_outline=_ring(circle + [6.0, 4.0]))]
    s0, m0 = _leaves(load_project(district(tmp_path / "plain", trees=plain, buildings=None)))
    s1, m1 = _leaves(load_project(district(tmp_path / "shaped", trees=shaped, buildings=None)))
    assert len(s0.instances) == len(s1.instances) == 2
    assert [i.__dict__ for i in s0.instances] == [i.__dict__ for i in s1.instances]
    assert s0.prototypes.keys() == s1.prototypes.keys()
    for k, proto in s0.prototypes.items():
        np.testing.assert_array_equal(proto[0].vertices, s1.prototypes[k][0].vertices)
    assert m0.keys() == m1.keys()
    assert any("outline(s) within 5% of the crown radius keep the spheroid" in n
               for n in s1.notes)


def test_inventory_L_crown_follows_its_outline(tmp_path: Path) -> None:
    """An L-shaped outline in longitude/latitude (projected like the position): the tree is
    built in place, its slat vertices within s/√2 of the L (centres inside), its top at the
    inventory height; the note says so."""
    from shapely.geometry import Polygon

    from radtree.site.inventory import LocalFrame

    lat, lon = -32.8895, -68.8458
    frame = LocalFrame("EPSG:4326", lat, lon)
    ring = L_RING + [0.0, 3.0]
    lo, la = frame.to_source(ring[:, 0], ring[:, 1])
    t_lon, t_lat = frame.to_source(np.array([0.0]), np.array([3.0]))
    trees = [point("T1", float(t_lon[0]), float(t_lat[0]),
                   crown_outline=_ring(np.column_stack([lo, la])))]
    p = load_project(district(tmp_path, trees=trees, buildings=None, crs=None))
    scene, meshes = _leaves(p)
    assert not scene.instances
    (mesh,) = meshes.values()
    v = mesh.vertices
    grown = Polygon(ring).buffer(0.3 / math.sqrt(2.0) + 1e-6)
    from shapely import contains_xy

    assert contains_xy(grown, v[:, 0], v[:, 1]).all()
    assert not contains_xy(Polygon(ring).buffer(-0.01), 4.9, 4.9)   # the L's missing corner
    assert v[:, 2].max() <= 8.0 + 0.3 and v[:, 2].min() >= 3.0 - 0.3
    assert any("1 crown(s) follow their crown_outline" in n for n in scene.notes)


def test_bad_outline_names_the_feature(tmp_path: Path) -> None:
    from radtree.site.inventory import read_trees

    bow = [[0, 0], [2, 2], [2, 0], [0, 2], [0, 0]]
    path = district(tmp_path, trees=[point("T9", 0.0, 3.0, crown_outline=bow)],
                    buildings=None) / "trees.geojson"
    with pytest.raises(ConfigError, match=r"feature 'T9'.*crown_outline is not a simple "
                                          r"polygon \(Self-intersection"):
        read_trees(path, "local", -32.8895, -68.8458)


def test_outline_reaching_a_wall_is_clipped_there(tmp_path: Path) -> None:
    """A crown of radius 2.5 m, 5 m from a wall, whose outline (an ellipse of semi-axes 2 m
    and 6 m) reaches 1 m into the building: the wall is found by the outline's reach and the
    crown is cut at the clip plane in front of it (policy "clip"), every slat south of it."""
    from radtree.trees.envelope import clip_plane
    from tests.test_district import box

    ring = np.column_stack([2.0 * np.cos(THETA), 5.0 + 6.0 * np.sin(THETA)])
    trees = [point("T1", 0.0, 5.0, crown_outline=_ring(ring))]
    p = load_project(district(tmp_path, trees=trees, buildings=[box("N1", -15, 10, 15, 22)]))
    scene, meshes = _leaves(p)
    (mesh,) = meshes.values()
    wall = 10.0 - clip_plane(p.tree, p.sensors)
    assert mesh.vertices[:, 1].max() <= wall + 1e-9
    assert mesh.vertices[:, 1].max() > wall - 0.05       # it does reach the plane
    assert any("crowns cut at the wall; crown volume removed: the crown of tree 'T1'" in n
               for n in scene.notes)


def test_turbid_crowns_stay_spheroids_with_a_note(tmp_path: Path) -> None:
    """Turbid inventory crowns keep the spheroid of crown_diameter_m and say so."""
    trees = [point("T1", 0.0, 3.0, crown_outline=_ring(L_RING + [0.0, 3.0]))]
    root = district(tmp_path, trees=trees, buildings=None)
    toml = root / "radtree.toml"
    toml.write_text(toml.read_text().replace('form = "free"',
                                             'form = "free"\nrepresentation = "turbid"'))
    from radtree.pipeline.assemble import make_scene

    p = load_project(root)
    scene = make_scene(p, p.scenario("T")).scene
    assert scene.media is not None and scene.media.a[0] == pytest.approx(2.5)
    assert any("1 tree(s) have a crown_outline that is not round: turbid crowns stay "
               "spheroids" in n for n in scene.notes)
