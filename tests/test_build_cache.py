"""The build cache (issue 22): crowns and their OBJ text kept between builds, keyed by all that
shapes them; a cached build writes the very same scene files; limits, bad entries, off."""

from __future__ import annotations

import logging
import os
import pickle

import numpy as np
import pytest
from click.testing import CliRunner

from radtree import cache
from radtree.config import load_project
from radtree.pipeline import build as build_mod
from radtree.pipeline.assemble import facade_frame
from radtree.pipeline.build import SCENE_FILE, build_project, folder_files
from radtree.trees.build import crown_in_cache
from tests.conftest import copy_project


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("RADTREE_CACHE_DIR", str(folder))
    monkeypatch.delenv("RADTREE_CACHE_MB", raising=False)
    return folder


def _scene_files(folder):
    return {k: v for k, v in folder_files(folder).items() if k != SCENE_FILE}


def test_a_fresh_build_takes_its_crowns_from_the_cache(tmp_path, cache_dir, monkeypatch,
                                                       caplog):
    """The second build (``--fresh``) loads B's louvers crown and copies its OBJ text: every
    scene file is byte-identical, though the louvers builder now fails; with all crowns
    cached the queue weights are 0 (no worker is spawned for them)."""
    p = load_project(copy_project(tmp_path / "proj", hours=["13:30"]))
    b, e = p.scenario("B"), p.scenario("E")
    assert build_mod._weight(p, b) == build_mod._weight(p, e) == 1
    assert not crown_in_cache(p, b, facade_frame(p))
    first = build_project(p, ["B", "E"], pictures=False, workers=1)
    assert not first["B"]["crown_from_cache"] and not first["E"]["crown_from_cache"]
    files = {n: _scene_files(p.build_dir / n) for n in ("B", "E")}
    assert any(k.endswith(".obj") for k in files["B"])
    kinds = sorted(f.suffix for f in cache_dir.iterdir())
    assert kinds.count(".pickle") == 2 and kinds.count(".obj") >= 1

    def broken(*args, **kwargs):
        raise AssertionError("the crown was built again")

    monkeypatch.setattr("radtree.trees.louvers.build_louvers", broken)  # the registry's
    assert crown_in_cache(p, b, facade_frame(p)) and build_mod._weight(p, b) == 0
    with caplog.at_level(logging.INFO, logger="radtree"):
        again = build_project(p, ["B", "E"], pictures=False, fresh=True)
    lines = [r.getMessage() for r in caplog.records if r.name == "radtree.pipeline.build"]
    assert again["B"]["crown_from_cache"] and again["E"]["crown_from_cache"]
    assert sum("(crown from the cache)" in line for line in lines) == 2
    assert {n: _scene_files(p.build_dir / n) for n in ("B", "E")} == files
    assert again["B"]["triangles"] == first["B"]["triangles"] > 1000


def test_a_switch_or_an_edited_input_file_is_another_crown(tmp_path, cache_dir):
    """A switch on the crown gives a new key; an input file counts by its bytes (a rewrite
    with the same bytes keeps the key, other bytes change it); off → nothing cached."""
    p = load_project(copy_project(tmp_path / "proj", hours=["13:30"],
                                  replace={r'^name = "B"$': 'name = "B"\nswitches = '
                                           '{ "louvers.layers" = 6 }'}))
    build_project(p, ["A"], pictures=False, workers=1)
    frame = facade_frame(p)
    assert crown_in_cache(p, p.scenario("A"), frame)
    assert not crown_in_cache(p, p.scenario("B"), frame)    # 6 layers: not A's crown
    photo = tmp_path / "photo.jpg"
    photo.write_bytes(b"\xff\xd8 one")
    k1 = cache.content_key(what="crown", photo=photo)
    photo.write_bytes(b"\xff\xd8 one")
    assert cache.content_key(what="crown", photo=photo) == k1
    photo.write_bytes(b"\xff\xd8 two")
    assert cache.content_key(what="crown", photo=photo) != k1
    moved = tmp_path / "elsewhere" / "photo.jpg"     # a copied project: the same file
    moved.parent.mkdir()
    moved.write_bytes(photo.read_bytes())
    assert cache.content_key(photo=moved) == cache.content_key(photo=photo)
    assert (cache.content_key(photo=moved, located=("photo",))
            != cache.content_key(photo=photo, located=("photo",)))   # its path is recorded
    a = np.arange(6.0)
    assert cache.content_key(a) != cache.content_key(a.reshape(2, 3))   # shape counts


def test_least_recently_used_entries_leave_first(cache_dir, monkeypatch):
    """At most RADTREE_CACHE_MB: the oldest by last use goes; a hit makes an entry recent."""
    monkeypatch.setenv("RADTREE_CACHE_MB", "2.5")
    blob = np.zeros(100_000)                       # 0.8 MB pickled
    for i, key in enumerate("abc"):
        obj, hit = cache.cached_object(key, lambda: blob + 1)
        assert not hit and obj.shape == blob.shape
        os.utime(cache_dir / f"{key}.pickle", (1000.0 + i, 1000.0 + i))
    _, hit = cache.cached_object("a", lambda: blob)  # a hit: "a" is now the most recent
    assert hit
    cache.cached_object("d", lambda: blob + 2)       # 4 × 0.8 MB > 2.5 MB: "b" leaves
    assert sorted(f.stem for f in cache_dir.glob("*.pickle")) == ["a", "c", "d"]
    info = cache.cache_info()
    assert info.entries == 3 and info.bytes <= 2.5e6 and info.limit == 2_500_000


def test_an_unreadable_entry_is_built_again(cache_dir):
    cache_dir.mkdir()
    (cache_dir / "k.pickle").write_bytes(b"half a pickle")
    obj, hit = cache.cached_object("k", lambda: {"crown": 7})
    assert (obj, hit) == ({"crown": 7}, False)
    assert pickle.loads((cache_dir / "k.pickle").read_bytes()) == {"crown": 7}
    assert cache.cached_object("k", lambda: None) == ({"crown": 7}, True)


def test_off_caches_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("RADTREE_CACHE_DIR", "off")
    assert cache.cache_dir() is None
    assert cache.cached_object("k", lambda: 3) == (3, False)
    dest = tmp_path / "m.obj"
    assert cache.cached_file("k", ".obj", lambda p: p.write_text("v 0 0 0\n"), dest) is False
    assert dest.read_text() == "v 0 0 0\n"
    assert "off" in cache.cache_info().describe()


def test_obj_text_is_copied_from_the_cache(tmp_path, cache_dir):
    made: list[int] = []

    def make(path) -> None:
        made.append(1)
        path.write_text("v 0.00000 1.00000 2.00000\n")

    assert cache.cached_file("m", ".obj", make, tmp_path / "a.obj") is False
    assert cache.cached_file("m", ".obj", make, tmp_path / "b.obj") is True
    assert made == [1] and (tmp_path / "b.obj").read_text() == (tmp_path / "a.obj").read_text()


def test_radtree_cache_command_shows_and_clears(cache_dir):
    from radtree.cli.cache import cache_command

    cache.cached_object("x", lambda: 1)
    cache.cached_object("y", lambda: 2)
    res = CliRunner().invoke(cache_command, [])
    assert res.exit_code == 0 and str(cache_dir) in res.output and "2 entries" in res.output
    res = CliRunner().invoke(cache_command, ["--clear"])
    assert res.exit_code == 0 and "removed 2 cache entries" in res.output
    assert "0 entries" in res.output and not list(cache_dir.glob("*.pickle"))


def test_the_crown_picture_is_copied_for_the_same_crown_and_scene(tmp_path, cache_dir,
                                                                   monkeypatch):
    """A second build draws no picture: model.png comes from the cache, the same bytes."""
    from radtree.trees import picture

    p = load_project(copy_project(tmp_path / "proj", hours=["13:30"]))
    build_project(p, ["E"], workers=1)
    png = (p.build_dir / "E" / "model.png").read_bytes()
    assert png[:4] == b"\x89PNG" and len(list(cache_dir.glob("*.png"))) == 1

    def no_drawing(*args, **kwargs):
        raise AssertionError("the picture was drawn again")

    monkeypatch.setattr(picture, "render_model_png", no_drawing)
    build_project(p, ["E"], fresh=True, workers=1)
    assert (p.build_dir / "E" / "model.png").read_bytes() == png
