"""Reliability under faults (issue 23): concurrent runs, killed engines, corrupt state, full
disks, signals, resource limits, determinism.

Every multi-process test is held at a known point (tests/held_run.py: a real radtree process
whose hour K + 1 waits for a signal), so none depends on timing. The project is the Mendoza
example reduced to an open street, one hour and 64 rays per sensor on the NumPy engine.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import load_project
from radtree.pipeline.results import read_results

from .conftest import copy_project, needs_radiance, radiance_available

HELD = str(Path(__file__).with_name("held_run.py"))
TINY = {r'model = "\w+"': 'model = "none"', r"^rays = \d+": "rays = 64",
        r"^dense_spacing_m = .*$": "dense_spacing_m = 3.0"}


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    """Open street, one hour (10:30), 64 rays per sensor, a coarse façade map."""
    return copy_project(tmp_path / "proj", TINY, hours=["10:30"])


def cli(*args: str):
    return CliRunner().invoke(main, list(args))


def error_lines(res) -> list[str]:  # type: ignore[no-untyped-def]
    """The lines of a command's stderr from its one ``error:`` line on (after progress bars)."""
    lines = res.stderr.splitlines()
    starts = [i for i, line in enumerate(lines) if line.startswith("error: ")]
    assert len(starts) == 1, res.stderr
    return lines[starts[0]:]


def _wait_for_parts(parts: Path, k: int, proc: subprocess.Popen) -> None:
    """Until ``k`` finished parts (CSV with its manifest) exist, or the process ended."""
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        if parts.exists() and len(list(parts.glob("*.csv.json"))) >= k:
            return
        time.sleep(0.05)


def held(k: int | None, *args: str, wait_for: str = "engine:") -> subprocess.Popen:
    """``radtree ARGS`` in a child process held at hour k + 1 (k None: not held), returned once
    its stdout has printed a line starting with ``wait_for``
    and, when held, its first k hours' parts are written (no race with a signal sent next)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    head = [HELD, str(k)] if k is not None else ["-m", "radtree.cli"]
    proc = subprocess.Popen([sys.executable, *head, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    stream = proc.stdout
    assert stream is not None
    for line in stream:
        if line.startswith(wait_for):
            proc.first_line = line  # type: ignore[attr-defined]
            if k is not None:
                _wait_for_parts(Path(args[1]) / "results" / "parts", k, proc)
            return proc
    raise AssertionError(f"{args} ended before printing {wait_for!r}: {proc.communicate()}")


# ---------------------------------------------------------------- 1. concurrent runs
def test_second_writer_is_refused_or_waits_and_readers_see_one_table(tiny: Path):
    sim = ["simulate", str(tiny), "--engine", "numpy", "-s", "A", "-s", "B"]
    assert cli(*sim).exit_code == 0
    before = read_results(load_project(tiny))
    shutil.rmtree(tiny / "results" / "parts")
    first = held(1, *sim)                              # holds results/ and build/
    try:
        res = cli(*sim)
        assert res.exit_code == 2
        assert res.stderr.splitlines()[-1].startswith(
            f"error: {tiny / 'results'} is in use by pid {first.pid} "
            f"(radtree simulate {tiny}), since ")
        assert "(or rerun with --wait)" in res.stderr
        assert cli("build", str(tiny)).exit_code == 2  # build/ is held too
        # a reader meanwhile sees the whole previous table (the new one is not written yet)
        pd.testing.assert_frame_equal(read_results(load_project(tiny)), before)
        waiter = held(None, *sim, "--wait", wait_for="waiting")
        assert waiter.first_line.strip() == (  # type: ignore[attr-defined]
            f"waiting for {_holder(first.pid, tiny)} to release {tiny / 'results'}")
        first.send_signal(signal.SIGINT)
        assert first.wait(60) == 130
        out, err = waiter.communicate(timeout=120)
        assert waiter.returncode == 0, err
        assert "1 hours traced, 1 reused" in out       # resumed where the first stopped
    finally:
        if first.poll() is None:
            first.kill()
    # publishing: while a writer replaces table, timing and manifest, readers wait (shared)
    from radtree.lock import PUBLISH_NAME, LockHeld, folder_lock, lock_path

    hold = ("import sys; from radtree.lock import folder_lock, PUBLISH_NAME\n"
            f"with folder_lock({str(tiny / 'results')!r}, 'radtree simulate', "
            "name=PUBLISH_NAME, shared=len(sys.argv) > 1):\n print('held', flush=True); "
            "sys.stdin.read()")
    for shared, refused in ((False, True), (True, False)):
        writer = subprocess.Popen([sys.executable, "-c", hold, *["shared"] * shared],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert writer.stdout is not None and writer.stdout.readline() == "held\n"
        try:
            with folder_lock(tiny / "results", "radtree report", name=PUBLISH_NAME,
                             shared=True):
                assert not refused
        except LockHeld as exc:
            assert refused and f"in use by pid {writer.pid} (radtree simulate)" in str(exc)
        writer.communicate("")
    # a lock left by a process that is gone is taken over, and said so
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    lock_path(tiny / "results").write_text(json.dumps(
        {"pid": dead.pid, "command": "radtree simulate elsewhere"}))
    res = cli(*sim)
    assert res.exit_code == 0, res.output
    assert (f"note: {tiny / 'results'} was locked by pid {dead.pid} (radtree simulate "
            "elsewhere), which is no longer running; lock taken over") in res.stdout


def _holder(pid: int, tiny: Path) -> str:
    from radtree.lock import lock_path

    lock = json.loads(lock_path(tiny / "results").read_text())
    return f"pid {pid} (radtree simulate {tiny}), since {lock['since']}"


# ---------------------------------------------------------------- 2. killed / failing engine
KILLER = """#!{python} -I
# rtrace for hour {hour} is SIGKILLed after {rows} rows of output, and so is this wrapper
import os, signal, subprocess, sys
real = {real!r}
if "octrees/{hour}.oct" not in sys.argv:
    os.execv(real, [real, *sys.argv[1:]])
child = subprocess.Popen([real, *sys.argv[1:]], stdout=subprocess.PIPE)
for n, line in enumerate(child.stdout, 1):
    sys.stdout.buffer.write(line)
    if n == {rows}:
        break
sys.stdout.flush()
child.kill()
child.wait()
os.kill(os.getpid(), signal.SIGKILL)
"""


def _killing_radiance(tmp_path: Path, hour: str, rows: int) -> Path:
    """A Radiance bin/ folder whose rtrace is killed mid-hour: the real programs linked in,
    rtrace replaced by a wrapper around the real one (KILLER)."""
    from radtree.engines.radiance.binaries import find_radiance

    real = find_radiance()
    assert real is not None
    bin_dir = tmp_path / "radiance" / "bin"
    bin_dir.mkdir(parents=True)
    if real.lib_dir is not None:
        (tmp_path / "radiance" / "lib").symlink_to(real.lib_dir)
    for prog in real.bin_dir.iterdir():
        (bin_dir / prog.name).symlink_to(prog)
    (bin_dir / "rtrace").unlink()
    (bin_dir / "rtrace").write_text(KILLER.format(python=sys.executable, hour=hour, rows=rows,
                                                  real=real.program("rtrace")))
    (bin_dir / "rtrace").chmod(0o755)
    return bin_dir


def _parts(project: Path) -> list[str]:
    return sorted(p.name.split("_")[1] for p in (project / "results" / "parts").glob("*.csv"))


@needs_radiance
def test_killed_or_failing_engine_names_scenario_and_hour_and_resumes(tmp_path, monkeypatch):
    from radtree.engines.radiance import binaries
    from radtree.engines.registry import engine_class

    proj = copy_project(tmp_path / "proj", TINY, hours=["10:30", "13:30"])
    sim = ["simulate", str(proj), "-s", "B", "--workers", "1"]
    # rtrace really killed (SIGKILL) after 3 of the 13:30 façade rows
    monkeypatch.setenv("RADTREE_RADIANCE", str(_killing_radiance(tmp_path, "1330", 3)))
    binaries.find_radiance.cache_clear()
    res = cli(*sim, "--engine", "radiance")
    assert res.exit_code == 3, res.output
    lines = error_lines(res)
    assert lines[0] == ("error: scenario B, hour 13:30: the radiance engine failed: rtrace was "
                        "killed by signal 9 (SIGKILL)")
    assert lines[1].startswith("  command: rtrace -h -I -u-") and lines[1].endswith("octrees/1330.oct")
    assert lines[-1] == ("  finished hours are kept in results/parts/; run the same command "
                         "again to resume")
    assert _parts(proj) == ["1030"]                        # the finished hour is kept
    assert not list((proj / "results").rglob(".*tmp")) and not list(
        (proj / "build" / "B" / "results").glob("1330_*"))  # no half-written output
    monkeypatch.delenv("RADTREE_RADIANCE")
    binaries.find_radiance.cache_clear()
    res = cli(*sim, "--engine", "radiance")
    assert res.exit_code == 0, res.output
    assert "1 hours traced, 1 reused" in res.stdout

    # the in-process NumPy engine raising (a fault injected around trace_many): it traces a
    # scenario's hours in one batch, so the error names both hours and nothing of B is kept
    cls = engine_class("numpy")
    original = cls.trace_many

    def failing(self, plan, labels, grids=None):  # type: ignore[no-untyped-def]
        raise MemoryError("cannot allocate 12.0 GiB for the ray bundle")

    monkeypatch.setattr(cls, "trace_many", failing)
    res = cli(*sim, "--engine", "numpy")
    assert res.exit_code == 3
    assert error_lines(res)[0] == (
        "error: scenario B, hours 10:30, 13:30: the numpy engine failed: MemoryError: cannot "
        "allocate 12.0 GiB for the ray bundle")
    assert not [p for p in (proj / "results" / "parts").glob("*numpy*.csv")]
    monkeypatch.setattr(cls, "trace_many", original)
    res = cli(*sim, "--engine", "numpy")
    assert res.exit_code == 0 and "2 hours traced, 0 reused" in res.stdout


# ---------------------------------------------------------------- 3. corrupt or stale state
def test_corrupt_parts_are_detected_and_recomputed(tiny: Path, tmp_path: Path):
    sim = ["simulate", str(tiny), "--engine", "numpy", "-s", "A", "-s", "B"]
    assert cli(*sim).exit_code == 0
    before = read_results(load_project(tiny))
    parts = tiny / "results" / "parts"
    a, b = sorted(parts.glob("*.csv"))
    size = a.stat().st_size
    a.write_bytes(a.read_bytes()[: size // 2])                      # truncated
    text = b.read_text()
    b.write_text(text.replace(",facade,0,", ",facade,9,", 1))       # hand-edited, same size
    res = cli(*sim)
    assert res.exit_code == 0, res.output
    assert res.stdout.splitlines()[1:3] == [
        f"  results/parts/{a.name} is truncated ({size // 2} of {size} bytes): recomputing it",
        f"  results/parts/{b.name} was changed after it was written (sha256 differs from its "
        "manifest): recomputing it"]
    assert "2 hours traced, 0 reused" in res.stdout
    pd.testing.assert_frame_equal(read_results(load_project(tiny)), before)  # same numbers
    (parts / f"{b.name}.json").unlink()                             # an interrupted write
    res = cli(*sim)
    assert (f"  results/parts/{b.name} has no valid manifest (an interrupted write or an older "
            "radtree): recomputing it") in res.stdout
    assert "1 hours traced, 1 reused" in res.stdout
    moved = tmp_path / "moved"                                      # a moved project keeps
    shutil.copytree(tiny, moved)                                    # its finished hours
    assert "0 hours traced, 2 reused" in cli(*sim[:1], str(moved), *sim[2:]).stdout
    dni = moved / "data" / "direct_normal_illuminance.csv"          # an edited input file
    dni.write_text(dni.read_text().replace("10:30,1", "10:30,"))    # does not
    assert "2 hours traced, 0 reused" in cli(*sim[:1], str(moved), *sim[2:]).stdout


@needs_radiance
def test_stale_build_folder_is_detected_and_rebuilt(tiny: Path):
    sim = ["simulate", str(tiny), "--engine", "radiance", "-s", "B"]
    assert "  build/B is missing: building it" in cli(*sim).stdout
    before = read_results(load_project(tiny))
    folder = tiny / "build" / "B"
    manifest = folder / "manifest.json"
    stamp = json.loads(manifest.read_text())

    def rerun(**change) -> list[str]:  # type: ignore[no-untyped-def]
        mf = json.loads(manifest.read_text())
        mf.update(change.get("top", {}))
        mf["build"].update(change.get("build", {}))
        manifest.write_text(json.dumps(mf))
        res = cli(*sim)
        assert res.exit_code == 0, res.output
        return [line for line in res.stdout.splitlines() if line.startswith("  build/B")]

    assert rerun(build={"params_hash": "0123456789ab"}) == [
        "  build/B was written for other parameters: building it"]
    assert rerun(top={"radtree_version": "0.0.1"}) == [
        f"  build/B was written by radtree 0.0.1 (this is {stamp['radtree_version']}): "
        "building it"]
    (folder / "geometry" / "ground.rad").unlink()
    assert rerun() == ["  build/B lacks geometry/ground.rad: building it"]
    (folder / "skies" / "1030.sky").write_text("# emptied by hand\n")
    assert rerun() == ["  build/B has skies/1030.sky changed since it was built: building it"]
    assert rerun() == []                                             # now current
    for octree in (folder / "octrees").glob("*.oct"):                # a deleted octree is
        octree.unlink()                                              # remade by oconv
    assert "1 hours traced, 0 reused" in cli(*sim, "--fresh").stdout
    assert (folder / "octrees" / "1030.oct").stat().st_size > 0
    pd.testing.assert_frame_equal(read_results(load_project(tiny)), before)


# ---------------------------------------------------------------- 4. full disk, folders, names
def test_atomic_writes_get_the_mode_open_would_give(tmp_path: Path):
    """Temporaries start at 0600; the renamed file and folder must not stay private."""
    import os

    import radtree.fileio as fileio
    from radtree.fileio import atomic_dir, write_text

    old = os.umask(fileio._UMASK)
    try:
        plain = tmp_path / "plain.txt"
        plain.write_text("x")
        atomic = write_text(tmp_path / "atomic.txt", "x")
        with atomic_dir(tmp_path / "folder") as tmp:
            (tmp / "f").write_text("x")
    finally:
        os.umask(old)
    assert atomic.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777
    assert (tmp_path / "folder").stat().st_mode & 0o777 == fileio.FOLDER_MODE


def test_failed_write_names_the_file_and_leaves_nothing_half_written(tmp_path: Path):
    from radtree.fileio import atomic_path, write_text

    target = write_text(tmp_path / "table.csv", "old,complete\n")
    with pytest.raises(OSError) as err, atomic_path(target) as tmp:
        tmp.unlink()
        tmp.symlink_to("/dev/full")              # the kernel's always-full device: ENOSPC
        tmp.write_text("new," * 10_000)
    assert err.value.filename == str(target)
    assert err.value.strerror == ("cannot write: No space left on device (nothing written; a "
                                  "previous table.csv, if any, is unchanged)")
    assert target.read_text() == "old,complete\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_full_disk_file_in_the_way_and_unusual_paths(tmp_path: Path):
    import resource

    proj = copy_project(tmp_path / "calle ñandú 1" / "proyecto", TINY, hours=["10:30"])
    sim = ["simulate", str(proj), "--engine", "numpy", "-s", "A"]
    # a file-size limit below one part: the write fails like a full disk (EFBIG, not a kill)
    limits = resource.getrlimit(resource.RLIMIT_FSIZE)
    xfsz = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (1000, limits[1]))
    try:
        res = cli(*sim)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, limits)
        signal.signal(signal.SIGXFSZ, xfsz)
    assert res.exit_code == 2, res.output
    part = next(iter(load_project(proj).scenarios)).name
    lines = error_lines(res)
    assert len(lines) == 1 and lines[0].startswith(f"error: {proj / 'results' / 'parts' / part}_")
    assert lines[0].endswith(".csv: cannot write: File too large (nothing written; a previous "
                             f"{lines[0].split('/')[-1].split(':')[0]}, if any, is unchanged)")
    assert list((proj / "results" / "parts").iterdir()) == []  # no part, no temporary
    # a file where an output folder belongs (also how a read-only folder looks to root)
    shutil.rmtree(proj / "results")
    (proj / "results").write_text("not a folder")
    res = cli(*sim)
    assert res.exit_code == 2
    assert error_lines(res) == [f"error: {proj / 'results' / 'parts'}: cannot create this "
                                f"folder: {proj / 'results'} is a file (move or delete it)"]
    (proj / "results").unlink()
    if os.geteuid() != 0:                        # a read-only folder (root may write anyway)
        (proj / "results").mkdir()
        (proj / "results").chmod(0o555)
        try:
            res = cli(*sim)
            assert res.exit_code == 2 and "Permission denied" in error_lines(res)[0]
        finally:
            (proj / "results").chmod(0o755)
    # spaces and non-ASCII letters in the path: both engines, build folder and lock
    res = cli(*sim)
    assert res.exit_code == 0 and "1 hours traced, 0 reused" in res.stdout
    if radiance_available():
        res = cli("simulate", str(proj), "--engine", "radiance", "-s", "B")
        assert res.exit_code == 0, res.output
    assert len(read_results(load_project(proj))) == 2 * len(
        read_results(load_project(proj)).query("scenario == 'A'")) or not radiance_available()


# ---------------------------------------------------------------- 6. resource limits
def test_too_big_a_project_is_refused_up_front_with_the_estimate(tiny: Path, tmp_path: Path):
    from radtree.pipeline.limits import available_memory, check_memory

    toml = tiny / "radtree.toml"
    toml.write_text(toml.read_text() + "\n[limits]\nmax_triangles = 5\n")
    for command in ("build", "simulate"):
        res = cli(command, str(tiny), "-s", "B", *(["--engine", "numpy"] * (command != "build")))
        assert res.exit_code == 2
        assert error_lines(res) == [
            f"error: {toml}, field 'limits.max_triangles': scenario B would build 6 triangles, "
            "more than the limit of 5: use larger slats (tree.louvers.slat_size_m), fewer "
            "layers (tree.louvers.layers) or a lower tree.perforated.resolution, or raise "
            "max_triangles in [limits]"]
    assert not (tiny / "results" / "parts").exists()
    toml.write_text(toml.read_text().replace("max_triangles = 5", "max_memory_fraction = 1e-6"))
    res = cli("simulate", str(tiny), "-s", "B", "--engine", "numpy", "--workers", "3")
    assert res.exit_code == 2
    line, = error_lines(res)
    head, tail = line.split(" GiB available")
    assert head.startswith(
        f"error: {toml}, field 'limits.max_memory_fraction': this run would need about 0.10 GiB "
        "(1 scene(s), 6 triangles, 3 worker(s)), more than 0.0001 % of the ")
    assert float(head.rsplit(" ", 1)[1]) > 0
    assert tail == (": use fewer --workers or scenarios at once (-s), a coarser crown model, "
                    "or raise max_memory_fraction in [limits]")
    assert not (tiny / "results" / "parts").exists()
    # the estimate: 200 B per triangle held + per worker 100 MiB + 300 B per traced triangle
    project = load_project(copy_project(tmp_path / "p2", TINY))
    with pytest.raises(Exception, match=r"need about 1\.87 GiB \(2 scene\(s\), 3,000,000 "
                       r"triangles, 2 worker\(s\)\), more than 80 % of the 1\.00 GiB"):
        check_memory(project, [1_000_000, 2_000_000], 2, available=2**30)
    check_memory(project, [1_000_000, 2_000_000], 2, available=3 * 2**30)  # fits: no error
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal:  24731184 kB\nMemFree:  1 kB\nMemAvailable:   22373456 kB\n")
    assert available_memory(meminfo) == 22373456 * 1024


# ---------------------------------------------------------------- 7. determinism
def _simulate_help_has(option: str) -> bool:
    return option in cli("simulate", "--help").output


def test_same_inputs_and_seed_give_the_same_table_whatever_workers_and_order(tmp_path: Path):
    engines = ["numpy"] + (["radiance"] if radiance_available() else [])
    runs = {"1 worker, A B D": (["-s", "A", "-s", "B", "-s", "D"], ["--workers", "1"]),
            "3 workers, D A B": (["-s", "D", "-s", "A", "-s", "B"], ["--workers", "3"])}
    if _simulate_help_has("--scheduler"):        # simulate on Dask (branch district)
        runs["dask, B D A"] = (["-s", "B", "-s", "D", "-s", "A"], ["--scheduler", "local"])
    for engine in engines:
        tables = {}
        for i, (name, (order, how)) in enumerate(runs.items()):
            proj = copy_project(tmp_path / f"{engine}{i}", TINY, hours=["10:30"])
            res = cli("simulate", str(proj), "--engine", engine, *order, *how)
            assert res.exit_code == 0, (name, res.output)
            tables[name] = (proj / "results" / "illuminance.csv").read_bytes()
        first = next(iter(tables.values()))
        assert all(t == first for t in tables.values()), engine   # byte for byte
        table = pd.read_csv(pd.io.common.BytesIO(first))
        assert list(dict.fromkeys(table["scenario"])) == ["A", "B", "D"]  # project order
        assert len(table) == 3 * (8 + 9)                        # 8 façade + 9 map sensors


# ---------------------------------------------------------------- values as written (finding 3)
@pytest.mark.parametrize("name, old, new, message", [
    ("direct_normal_illuminance.csv", "10:30,109170", "10:30,nan",
     "direct normal illuminance table {path}: data row 1: direct_normal_lux = 'nan' is not a "
     "non-negative number"),
    ("direct_normal_illuminance.csv", "10:30,109170", "10:30,inf",
     "direct normal illuminance table {path}: data row 1: direct_normal_lux = 'inf' is not a "
     "non-negative number"),
    ("concrete_reflectance.csv", "50,0.151", "50,NaN",
     "ground reflectance table {path}: data row 1: reflectance = 'NaN' is not a non-negative "
     "number"),
    ("concrete_reflectance.csv", "50,0.151", "nan,0.151",
     "ground reflectance table {path}: data row 1: angle_deg = 'nan' is not a sun altitude "
     "0–90°"),
])
def test_bad_table_values_are_shown_as_written(tiny: Path, name, old, new, message):
    path = tiny / "data" / name
    path.write_text(path.read_text().replace(old, new, 1))
    res = cli("simulate", str(tiny), "--engine", "numpy", "-s", "A", "--dry-run")
    assert res.exit_code == 2
    assert error_lines(res) == ["error: " + message.format(path=path)]
