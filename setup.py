"""Build hook: ship the top-level ``templates/`` and ``materials/`` inside the wheel.

They are mapped as the data subpackages ``radtree.templates`` and ``radtree.materials``, so an
installed radtree finds them beside its code (see ``radtree/resources.py``). Everything else
about the build is in pyproject.toml.
"""

from pathlib import Path

from setuptools import find_packages, setup

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

setup(
    packages=[*find_packages(include=["radtree", "radtree.*"]), *DATA_PACKAGES],
    package_dir=DATA_PACKAGES,
    package_data={p: ["*.j2", "*.rad", "*.md", "*.toml"] for p in DATA_PACKAGES},
    include_package_data=False,
)
