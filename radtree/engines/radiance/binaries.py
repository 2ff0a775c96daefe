"""Finding Radiance: the binaries of the ``pyradiance`` wheel, else a Radiance on PATH.

Radiance needs RAYPATH to point at its ``.cal`` library (``rayinit.cal``), or even
``rtrace -version`` fails. :func:`radiance_env` returns an environment with PATH and RAYPATH
set; the generated Makefiles set the same two variables themselves.
"""

from __future__ import annotations

import functools
import os
import shutil
import signal
import subprocess
from dataclasses import dataclass
from pathlib import Path

from radtree.errors import EngineError

REQUIRED = ("oconv", "rtrace", "gendaylit", "rcalc", "obj2mesh")   # obj2mesh: crowns (meshes.py)
#: rtrace/rcontrib/rfluxmtx's fixed-seed sampling: the same octree and options give the same
#: numbers in one process (Radiance's default ``-u+`` seeds its random numbers from the clock).
FIXED_SEED = "-u-"


def monte_carlo_options(ab: int, ad: int, lw: float) -> list[str]:
    """rtrace's ambient options for a pure Monte Carlo answer: ``-ab ab -ad ad -as 0 -aa 0
    -lw lw`` — no irradiance cache and no ambient super-sampling. Every ``rtrace`` that serves
    as a reference (``radtree verify``, the tests, the benchmarks) takes these.

    ``-as 0`` matters. With ``-aa 0`` rtrace still super-samples (its default ``-as`` is 512):
    it adds samples to the hemisphere divisions whose first samples differ most from their
    neighbours (Radiance ``src/rt/ambcomp.c``, ``samp_hemi`` → ``ambsupersamp``). Choosing where
    to add samples from the samples' own values biases the estimate (Kirk & Arvo 1991, "Unbiased
    sampling techniques for image synthesis", SIGGRAPH '91; cited from memory): a division whose
    first sample caught a rare bright path is re-averaged down, one that missed it is not.
    ``rcontrib`` turns super-sampling off itself (``src/rt/rcmain.c``, ``override_options``:
    ``ambssamp = 0``), and so do radtree's engine defaults (``engine.as = 0``).
    Measured (8 Dec 2026): the honeybee-office example's office 2 behind its leafed crown, a
    uniform sky, ``-ab 4 -ad 1024 -lw 1e-4``, mean of 96 sensors: 4.78 lx with rtrace's
    default ``-as``, 5.41 and 5.46 with ``-as 0``, 5.43 from ``rcontrib``; the default creeps
    up only with ``-ad`` (4 096: 5.15, 16 384: 5.32, 65 536 with ``-lw 1e-7``: 5.415).
    Behind the small louvers crown of :mod:`radtree.verify.annual` (``-ab 2 -ad 4096``, 4 hours) the
    two differ by ≤ 1.4 % a sensor, ≤ 0.5 % on the mean.
    """
    return ["-ab", str(ab), "-ad", str(ad), "-as", "0", "-aa", "0", "-lw", f"{lw:g}"]


@dataclass(frozen=True)
class RadianceInstall:
    """Where Radiance lives: ``bin_dir`` holds the programs, ``lib_dir`` the .cal library."""

    bin_dir: Path
    lib_dir: Path | None
    origin: str  # "pyradiance" or "PATH"

    def program(self, name: str) -> str:
        return str(self.bin_dir / name)

    def env(self) -> dict[str, str]:
        env = dict(os.environ)
        env["PATH"] = f"{self.bin_dir}{os.pathsep}{env.get('PATH', '')}"
        raypath = ["."]
        if self.lib_dir is not None:
            raypath.append(str(self.lib_dir))
        if env.get("RAYPATH"):
            raypath.append(env["RAYPATH"])
        env["RAYPATH"] = os.pathsep.join(raypath)
        return env

    @property
    def raypath(self) -> str:
        return self.env()["RAYPATH"]


def _from_pyradiance() -> RadianceInstall | None:
    try:
        import importlib.util

        spec = importlib.util.find_spec("pyradiance")
    except (ImportError, ValueError):
        return None
    if spec is None or spec.origin is None:
        return None
    root = Path(spec.origin).parent
    bin_dir, lib_dir = root / "bin", root / "lib"
    if all((bin_dir / p).exists() for p in REQUIRED):
        return RadianceInstall(bin_dir, lib_dir if lib_dir.exists() else None, "pyradiance")
    return None


def _from_path() -> RadianceInstall | None:
    rtrace = shutil.which("rtrace")
    if rtrace is None:
        return None
    bin_dir = Path(rtrace).resolve().parent
    if not all((bin_dir / p).exists() for p in REQUIRED):
        return None
    for cand in (bin_dir.parent / "lib", bin_dir.parent / "lib" / "ray", Path("/usr/local/lib/ray")):
        if (cand / "rayinit.cal").exists():
            return RadianceInstall(bin_dir, cand, "PATH")
    return RadianceInstall(bin_dir, None, "PATH")


def _from_env(value: str) -> RadianceInstall:
    """``RADTREE_RADIANCE=DIR``: the Radiance programs in DIR (its ``../lib`` the library)."""
    bin_dir = Path(value).expanduser()
    missing = [p for p in REQUIRED if not (bin_dir / p).exists()]
    if missing:
        raise EngineError(f"RADTREE_RADIANCE={value}: no {', '.join(missing)} in that folder "
                          "(set it to the bin/ folder of a Radiance installation, or unset it)")
    lib = next((c for c in (bin_dir.parent / "lib", bin_dir.parent / "lib" / "ray")
                if (c / "rayinit.cal").exists()), None)
    return RadianceInstall(bin_dir, lib, "RADTREE_RADIANCE")


@functools.lru_cache(maxsize=1)
def find_radiance() -> RadianceInstall | None:
    """The Radiance to use, or None: ``RADTREE_RADIANCE=DIR`` (a bin/ folder) when set, else
    the pyradiance wheel's, else one on PATH. ``RADTREE_NO_RADIANCE=1`` hides it."""
    if os.environ.get("RADTREE_NO_RADIANCE") == "1":
        return None
    if os.environ.get("RADTREE_RADIANCE"):
        return _from_env(os.environ["RADTREE_RADIANCE"])
    return _from_pyradiance() or _from_path()


def require_radiance() -> RadianceInstall:
    install = find_radiance()
    if install is None:
        raise EngineError(
            "Radiance was not found: install the 'pyradiance' package (pip install pyradiance) "
            "or put a Radiance installation on PATH, or use --engine numpy"
        )
    return install


def run(cmd: list[str], *, stdin: bytes | None = None, cwd: str | Path | None = None,
        stdout_path: Path | None = None) -> bytes:
    """Run a Radiance program (argument list, no shell); failures raise :class:`EngineError`."""
    install = require_radiance()
    argv = [install.program(cmd[0]) if (install.bin_dir / cmd[0]).exists() else cmd[0], *cmd[1:]]
    try:
        if stdout_path is not None:
            with open(stdout_path, "wb") as out:
                proc = subprocess.run(argv, input=stdin, stdout=out, stderr=subprocess.PIPE,
                                      cwd=cwd, env=install.env(), check=False)
            output = b""
        else:
            proc = subprocess.run(argv, input=stdin, capture_output=True, cwd=cwd,
                                  env=install.env(), check=False)
            output = proc.stdout
    except OSError as exc:
        raise EngineError(f"could not start {cmd[0]}: {exc}", command=cmd) from exc
    if proc.returncode != 0:
        raise EngineError(f"{cmd[0]} {_how(proc.returncode)}", command=cmd,
                          stderr=proc.stderr.decode(errors="replace"))
    return output


def _how(returncode: int) -> str:
    """``failed (exit 1)`` or, for a negative code, ``was killed by signal 9 (SIGKILL)``."""
    if returncode < 0:
        try:
            name = f" ({signal.Signals(-returncode).name})"
        except ValueError:
            name = ""
        return f"was killed by signal {-returncode}{name}"
    return f"failed (exit {returncode})"


def version() -> str | None:
    """``rtrace -version`` of the Radiance found, or None."""
    if find_radiance() is None:
        return None
    try:
        return run(["rtrace", "-version"]).decode().strip()
    except EngineError:
        return None
