"""The shipped chestnut photo (Coolpix 4500 + FC-E8) through the pipeline and the CLI."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from radtree.cli import main
from radtree.cli.hemi import hemi_command
from radtree.hemi import (
    HemiConfig,
    HemiResult,
    RingGrid,
    analyse_image,
    get_lens,
    render_fisheye,
)
from radtree.hemi.mask import CircularMask
from tests.conftest import CHESTNUT

PHOTO = CHESTNUT
pytestmark = pytest.mark.skipif(not PHOTO.exists(), reason="shared test photo not available")
GRID = RingGrid(5, 8, 0.0, 75.0)


@pytest.fixture(scope="module")
def result() -> HemiResult:
    return analyse_image(PHOTO, HemiConfig(preset="coolpix4500-fce8", grid=GRID))


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def independent_ring_gaps(result: HemiResult) -> np.ndarray:
    """Ring gap fractions by plain pixel counting, with our own FC-E8 inversion."""
    sky = result.classification.sky
    pf = result.pixel_field
    yy, xx = np.mgrid[pf.rows, pf.cols]
    rho = np.hypot(xx + 0.5 - 1136, yy + 0.5 - 852) / 754
    x = np.linspace(0, 1, 20001)
    p = 1.06 * x + 0.00498 * x**2 - 0.0639 * x**3
    zen = np.where(rho <= 1, np.interp(rho, p / p[-1], 90 * x), np.nan)
    edges = GRID.ring_edges
    return np.array([sky[(zen >= a) & (zen < b)].mean() for a, b in zip(edges[:-1], edges[1:])])


def test_pipeline_ranges_and_consistency(result: HemiResult) -> None:
    m = result.metrics
    assert 0 < result.classification.threshold < 255
    assert np.all((result.table.gap >= 0) & (result.table.gap <= 1))
    assert 0 < m.gap_fraction < 1 and 0 < m.openness < 1 and 0 < m.svf < 1
    assert 0 < m.difn < 100
    assert math.isfinite(m.lai_eff) and m.lai_eff > 0
    assert math.isfinite(m.lai) and m.lai >= m.lai_eff
    assert 0 < m.clumping_lx <= 1
    assert 0.05 <= m.ellipsoid_x <= 20 and 0 < m.mean_tilt_deg < 90
    # openness and SVF from ring gap fractions computed here, independently of radtree
    ring = independent_ring_gaps(result)
    w_open = GRID.ring_solid_angle_weights()
    w_svf = GRID.ring_cosine_weights()
    assert w_open.sum() == pytest.approx(1 - math.cos(math.radians(75)))
    assert m.openness == pytest.approx((w_open * ring).sum() / w_open.sum(), rel=0.02)
    assert m.svf == pytest.approx((w_svf * ring).sum() / w_svf.sum(), rel=0.02)
    assert result.table.ring_gap == pytest.approx(ring, rel=0.02)
    # Miller's LAI from those ring gap fractions
    k = -np.log(ring) * np.cos(np.radians(GRID.ring_centres))
    assert m.lai_eff == pytest.approx(2 * (k * w_open).sum() / w_open.sum(), rel=0.03)


def test_outlines_and_predicate_agree_with_classification(result: HemiResult) -> None:
    assert len(result.outlines) > 100
    total = sum(g.solid_angle_sr for g in result.outlines)
    sky_sr = result.pixel_field.weight[result.classification.sky].sum()
    assert 0.9 * sky_sr < total <= sky_sr * (1 + 1e-9)  # only gaps below 4 px are left out
    for g in result.outlines[:20]:
        assert np.all((g.exterior[:, 0] >= 0) & (g.exterior[:, 0] <= 90))
        assert np.all((g.exterior[:, 1] >= 0) & (g.exterior[:, 1] < 360))
    # the predicate samples the classified pixels: compare with pixel centres
    pf = result.pixel_field
    rng = np.random.default_rng(2)
    rows = rng.integers(0, pf.valid.shape[0], 5000)
    cols = rng.integers(0, pf.valid.shape[1], 5000)
    keep = pf.valid[rows, cols]
    rows, cols = rows[keep], cols[keep]
    is_sky = result.sky_predicate()
    got = is_sky(pf.zenith[rows, cols], pf.azimuth[rows, cols])
    assert np.mean(got == result.classification.sky[rows, cols]) > 0.999


def test_cli_end_to_end(result: HemiResult, tmp_path: Path) -> None:
    out = tmp_path / "out"
    res = CliRunner().invoke(
        hemi_command,
        [str(PHOTO), "--preset", "coolpix4500-fce8", "--rings", "5", "--segments", "8",
         "--zenith", "0,75", "--out", str(out)],
    )
    assert res.exit_code == 0, res.output
    stem = PHOTO.stem
    for name in ("summary.csv", "rings.csv", "gaps.geojson", f"{stem}_gaps.geojson",
                 f"{stem}_overlay.png"):
        assert (out / name).stat().st_size > 0, name
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries

    (row,) = read_csv(out / "summary.csv")
    for col in ("image", "threshold", "gap_fraction", "openness", "svf", "difn", "lai_eff",
                "lai", "clumping_lx", "ellipsoid_x", "mean_tilt_deg"):
        assert row[col] != "", col
    assert row["image"] == PHOTO.name
    m = result.metrics
    assert float(row["openness"]) == pytest.approx(m.openness, rel=1e-9)
    assert float(row["svf"]) == pytest.approx(m.svf, rel=1e-9)
    assert float(row["difn"]) == pytest.approx(m.difn, rel=1e-9)
    assert float(row["lai_eff"]) == pytest.approx(m.lai_eff, rel=1e-9)
    assert float(row["threshold"]) == pytest.approx(result.classification.threshold)

    rings = read_csv(out / "rings.csv")
    assert len(rings) == 5 * 8
    assert {r["ring"] for r in rings} == {"1", "2", "3", "4", "5"}
    gap = np.array([float(r["gap_fraction"]) for r in rings])
    gap_cos = np.array([float(r["gap_fraction_cos"]) for r in rings])
    w_open = np.array([float(r["weight_openness"]) for r in rings])
    w_svf = np.array([float(r["weight_svf"]) for r in rings])
    assert np.all((gap >= 0) & (gap <= 1))
    assert w_open.sum() == pytest.approx(1.0) and w_svf.sum() == pytest.approx(1.0)
    assert float(row["openness"]) == pytest.approx((w_open * gap).sum(), rel=1e-8)
    assert float(row["svf"]) == pytest.approx((w_svf * gap_cos).sum(), rel=1e-8)

    data = json.loads((out / "gaps.geojson").read_text())
    assert data["type"] == "FeatureCollection"
    assert len(data["features"]) == len(result.outlines)
    first = data["features"][0]
    assert first["geometry"]["type"] == "Polygon" and first["properties"]["image"] == PHOTO.name
    ring0 = np.array(first["geometry"]["coordinates"][0])
    assert np.allclose(ring0[0], ring0[-1]) and np.all((ring0[:, 1] >= 0) & (ring0[:, 1] <= 90))
    per_image = json.loads((out / f"{stem}_gaps.geojson").read_text())
    assert per_image["features"] == data["features"]
    with Image.open(out / f"{stem}_overlay.png") as im:
        assert im.format == "PNG" and min(im.size) >= 500
    assert "openness" in res.output


def test_cli_lens_and_mask_equal_the_preset(result: HemiResult, tmp_path: Path) -> None:
    res = CliRunner().invoke(
        hemi_command,
        [str(PHOTO), "--lens", "FC-E8", "--mask", "1136,852,754", "--rings", "5", "--zenith",
         "0,75", "--no-overlay", "--out", str(tmp_path)],
    )
    assert res.exit_code == 0, res.output
    (row,) = read_csv(tmp_path / "summary.csv")
    assert float(row["svf"]) == pytest.approx(result.metrics.svf, rel=1e-9)
    assert not (tmp_path / f"{PHOTO.stem}_overlay.png").exists()


def test_batch_over_a_folder(tmp_path: Path) -> None:
    """Folder mode on small synthetic photos (the real photo is covered above)."""
    photos = tmp_path / "photos"
    photos.mkdir()
    for name, theta0 in (("a.png", 30.0), ("b.PNG", 50.0)):
        sky = render_fisheye(lambda z, a, t=theta0: z < t, (400, 300))
        inside = render_fisheye(lambda z, a: np.ones(z.shape, bool), (400, 300)) > 0
        rgb = np.zeros((300, 400, 3), np.uint8)
        rgb[inside] = (20, 30, 25)
        rgb[sky > 0] = (160, 200, 250)
        Image.fromarray(rgb).save(photos / name)
    (photos / "0_broken.jpg").write_bytes(b"\xff\xd8\xff\xe0 not really a jpeg")
    (photos / "notes.txt").write_text("ignored")
    out = tmp_path / "out"
    args = [str(photos), "--mask", "200,150,150", "--no-overlay", "--out", str(out)]
    res = CliRunner().invoke(main, ["hemi", *args])
    assert res.exit_code == 2 and "0_broken.jpg" in res.output  # bad input
    assert not (out / "summary.csv").exists()  # failed before writing the tables
    res = CliRunner().invoke(main, ["hemi", *args, "--keep-going"])
    assert res.exit_code == 2 and "0_broken.jpg" in res.output
    rows = read_csv(out / "summary.csv")
    assert [r["image"] for r in rows] == ["a.png", "b.PNG"]
    for row, theta0 in zip(rows, (30.0, 50.0)):
        assert float(row["openness"]) == pytest.approx(1 - math.cos(math.radians(theta0)), rel=0.01)
    assert (out / "a_gaps.geojson").exists() and (out / "b_gaps.geojson").exists()
    merged = json.loads((out / "gaps.geojson").read_text())
    assert {f["properties"]["image"] for f in merged["features"]} == {"a.png", "b.PNG"}
    assert len(read_csv(out / "rings.csv")) == 2 * 9 * 8


def test_other_thresholds_and_channels(result: HemiResult) -> None:
    base = dict(lens=get_lens("FC-E8"), mask=CircularMask(1136, 852, 754), grid=GRID,
                outlines=False)
    iso = analyse_image(PHOTO, HemiConfig(threshold="isodata", **base))  # type: ignore[arg-type]
    zonal = analyse_image(PHOTO, HemiConfig(threshold="zonal", **base))  # type: ignore[arg-type]
    manual = analyse_image(PHOTO, HemiConfig(threshold=200, **base))  # type: ignore[arg-type]
    luma = analyse_image(PHOTO, HemiConfig(channel="luma", **base))  # type: ignore[arg-type]
    assert zonal.classification.ring_thresholds is not None
    assert len(zonal.classification.ring_thresholds) == 5
    assert manual.classification.threshold == 200
    assert manual.metrics.openness < result.metrics.openness  # stricter threshold, less sky
    for r in (iso, zonal, luma):
        assert 0 < r.classification.threshold < 255
        assert r.metrics.openness == pytest.approx(result.metrics.openness, rel=0.5)
