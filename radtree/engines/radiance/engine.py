"""Running a Radiance build folder: oconv → rtrace -I per hour, in Python or via its Makefile.

The Python runner executes exactly the commands the generated Makefile holds (argument lists,
no shell), writing every output to a temporary name first.
"""

from __future__ import annotations

import os
import tempfile
import threading
from pathlib import Path

import numpy as np

from radtree.config import EngineParams
from radtree.engines.base import GridResult
from radtree.engines.radiance.binaries import require_radiance, run
from radtree.engines.radiance.writer import BuildPlan, rgb_to_lux, write_build
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.scene import Scene

ENGINE_NAME = "radiance"
DEFAULT_AB = 2


def _hour_steps(plan: BuildPlan, hour: str, grids: list[str] | None, *, shared: bool
                ) -> list[tuple[list[str], str | None, str]]:
    """The hour's commands as (argv, stdin file, stdout file) relative to the folder: the
    shared inputs (compiled meshes, prototype octrees) when ``shared``, the octree, the photon
    map when asked for, one ``rtrace`` per grid of ``grids`` (None: every grid)."""
    steps: list[tuple[list[str], str | None, str]] = [
        (argv, None, out) for argv, out in [*plan.mesh_commands(), *plan.prototype_commands()]
    ] if shared else []
    steps.append((plan.oconv_command(hour), None, f"octrees/{hour}.oct"))
    mkpmap = plan.mkpmap_command(hour)
    if mkpmap is not None:
        steps.append((mkpmap, None, f"pmaps/{hour}.log"))
    for g in plan.grids:
        if grids is None or g in grids:
            steps.append((plan.rtrace_command(hour, g), f"grids/{g}.pts",
                          f"results/{hour}_{g}.rgb"))
    return steps


def hour_commands(plan: BuildPlan, hour: str, *, grids: list[str] | None = None) -> list[str]:
    """The shell lines that trace the hour (``(cd FOLDER && argv < in > out)``), the hours'
    shared inputs first; nothing runs."""
    return [f"(cd {plan.folder} && " + " ".join(argv) + (f" < {stdin}" if stdin else "")
            + f" > {stdout})" for argv, stdin, stdout in _hour_steps(plan, hour, grids,
                                                                      shared=True)]


def run_hour(plan: BuildPlan, hour: str, *, grids: list[str] | None = None
             ) -> dict[str, GridResult]:
    """Build the hour's octree and trace every grid (or ``grids``); return lux per grid."""
    folder = plan.folder
    commands = _hour_steps(plan, hour, grids, shared=False)
    use = [g for g in plan.grids if grids is None or g in grids]
    mkpmap = plan.mkpmap_command(hour)
    (folder / "octrees").mkdir(exist_ok=True)
    (folder / "results").mkdir(exist_ok=True)
    if mkpmap is not None:
        (folder / "pmaps").mkdir(exist_ok=True)
    results: dict[str, GridResult] = {}
    ensure_shared_inputs(plan)
    for argv, stdin, stdout in commands:
        _produce(folder, argv, stdin, stdout)
    for g in use:
        rgb_path = folder / f"results/{hour}_{g}.rgb"
        lux = read_rgb_as_lux(rgb_path, expected=None)
        lux_path = folder / f"results/{hour}_{g}.lux"
        tmp = lux_path.with_name(f"{lux_path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
        np.savetxt(tmp, lux, fmt="%.6g")
        os.replace(tmp, lux_path)
        results[g] = GridResult(lux, None)
    return results


def ensure_shared_inputs(plan: BuildPlan) -> None:
    """Make the folder's missing compiled meshes (``obj2mesh``) and prototype octrees, each
    once even when two hours of the folder run in two threads."""
    folder = plan.folder
    for argv, stdout in [*plan.mesh_commands(), *plan.prototype_commands()]:
        target = folder / stdout
        if target.exists():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        with _lock_for(target):
            if not target.exists():
                _produce(folder, argv, None, stdout)


_LOCKS: dict[Path, threading.Lock] = {}
_LOCKS_GUARD = threading.Lock()


def _lock_for(path: Path) -> threading.Lock:
    with _LOCKS_GUARD:
        return _LOCKS.setdefault(path, threading.Lock())


def _produce(folder: Path, argv: list[str], stdin: str | None, stdout: str) -> None:
    """Run ``argv`` in ``folder`` (stdin from a file), its output to a temporary name first."""
    out = folder / stdout
    tmp = out.with_name(f"{out.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    data = (folder / stdin).read_bytes() if stdin else None
    try:
        run(argv, stdin=data, cwd=folder, stdout_path=tmp)
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()


def read_rgb_as_lux(path: Path, expected: int | None) -> np.ndarray:
    """Read ``rtrace -I -h`` output (R G B per line) and convert to lux."""
    try:
        rows = np.loadtxt(path, ndmin=2)
    except (OSError, ValueError) as exc:
        raise EngineError(f"cannot read rtrace output {path}: {exc}") from exc
    if rows.size == 0 or rows.shape[1] < 3:
        raise EngineError(f"rtrace output {path} is empty or malformed")
    if expected is not None and len(rows) != expected:
        raise EngineError(f"rtrace output {path} has {len(rows)} values, expected {expected}")
    return rgb_to_lux(rows[:, :3])


def trace_hour(scene: Scene, state: SkyState, params: EngineParams,
               grids: list[str] | None = None, seed: int | None = None,
               workdir: Path | None = None, ab: int | None = None) -> dict[str, GridResult]:
    """Trace one hour with Radiance in a (temporary) build folder; lux per grid.

    ``ab`` overrides ``params.ab``; when both are None, ``-ab 2``. ``seed`` is unused: with ``-u-``
    Radiance's sampling is repeatable for a given octree and options.
    """
    install = require_radiance()
    use_ab = ab if ab is not None else (params.ab if params.ab is not None else DEFAULT_AB)
    if grids is not None:
        missing = [g for g in grids if g not in scene.grids]
        if missing:
            raise EngineError(f"unknown sensor grid(s): {', '.join(missing)}")
        scene = Scene(scene.meshes, scene.materials, {g: scene.grids[g] for g in grids},
                      scene.notes, scene.ground_material)
    if workdir is None:
        with tempfile.TemporaryDirectory(prefix="radtree-") as tmp:
            plan = write_build(scene, [state], params, use_ab, Path(tmp), install)
            return run_hour(plan, state.label)
    plan = write_build(scene, [state], params, use_ab, Path(workdir), install)
    return run_hour(plan, state.label)
