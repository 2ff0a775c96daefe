"""Build hook: ship the top-level ``templates/`` and ``materials/`` inside the wheel, and build
the NumPy engine's optional C kernel.

The folders are mapped as the data subpackages ``radtree.templates`` and ``radtree.materials``,
so an installed radtree finds them beside its code (see ``radtree/resources.py``).

``radtree.engines.common._kernel`` (``radtree/engines/common/_kernel.c``, the shadow-ray loop's
per-crossing arithmetic in one pass) is optional: without a C compiler the install goes on and
the engine runs its NumPy code, which gives the same numbers (``radtree doctor`` says which is
in use; ``RADTREE_KERNEL=numpy`` forces NumPy). It is compiled without floating-point
contraction (no fused multiply-add) or fast-math, so that it computes every number exactly as
NumPy does. Everything else about the build is in pyproject.toml.
"""

from pathlib import Path

from setuptools import Extension, find_packages, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).parent
DATA = ("templates", "materials")


def _data_packages() -> dict[str, str]:
    """``radtree.<folder>[.<sub>]`` → its folder, for every directory under DATA."""
    out = {}
    for top in DATA:
        for d in sorted([HERE / top, *(p for p in (HERE / top).rglob("*") if p.is_dir())]):
            if d.name == "__pycache__":
                continue
            rel = d.relative_to(HERE)
            out[".".join(("radtree", *rel.parts))] = rel.as_posix()
    return out


DATA_PACKAGES = _data_packages()

# IEEE arithmetic as NumPy does it: no contraction into fused multiply-adds, no reassociation
STRICT_FP = {"msvc": ["/O2", "/fp:precise"],
             "unix": ["-O2", "-ffp-contract=off", "-fno-fast-math"]}

KERNEL = Extension("radtree.engines.common._kernel", sources=["radtree/engines/common/_kernel.c"],
                   optional=True)


class BuildExt(build_ext):
    """The kernel's floating-point flags for the compiler at hand (gcc/clang or MSVC)."""

    def build_extensions(self) -> None:
        flags = STRICT_FP.get(self.compiler.compiler_type, STRICT_FP["unix"])
        for ext in self.extensions:
            ext.extra_compile_args = [*flags, *ext.extra_compile_args]
        super().build_extensions()


setup(
    packages=[*find_packages(include=["radtree", "radtree.*"]), *DATA_PACKAGES],
    package_dir=DATA_PACKAGES,
    package_data={p: ["*.j2", "*.rad", "*.md", "*.toml"] for p in DATA_PACKAGES},
    include_package_data=False,
    ext_modules=[KERNEL],
    cmdclass={"build_ext": BuildExt},
)
