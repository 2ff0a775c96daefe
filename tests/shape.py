"""The code's shape (issue 42): long functions and long positional parameter lists.

    .venv/bin/python -m tests.shape          # the ten longest functions, the ratchet's lists

A function of more than :data:`MAX_LINES` lines, or with more than :data:`MAX_POSITIONAL`
positional parameters (``self``/``cls`` not counted; keyword-only ones are free), is listed.
``tests/test_layers.py`` holds each count at or below the figure recorded there (a ratchet:
lower it when a change shortens the list, never raise it).
"""

from __future__ import annotations

import ast
import pathlib
from dataclasses import dataclass

MAX_LINES = 80
MAX_POSITIONAL = 8
ROOT = pathlib.Path(__file__).resolve().parents[1] / "radtree"


@dataclass(frozen=True)
class Function:
    where: str        # radtree/module.py:qualified.name
    lines: int
    positional: int


def _visit(node: ast.AST, rel: str, prefix: str, out: list[Function]) -> None:
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = child.args.posonlyargs + child.args.args
            n = len(args) - (1 if args and args[0].arg in ("self", "cls") else 0)
            length = (child.end_lineno or child.lineno) - child.lineno + 1
            out.append(Function(f"{rel}:{prefix}{child.name}", length, n))
            _visit(child, rel, f"{prefix}{child.name}.", out)
        elif isinstance(child, ast.ClassDef):
            _visit(child, rel, f"{prefix}{child.name}.", out)


def functions(root: pathlib.Path = ROOT) -> list[Function]:
    """Every function and method under ``root`` with its length and positional count."""
    out: list[Function] = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        _visit(tree, path.relative_to(root.parent).as_posix(), "", out)
    return out


def long_functions() -> list[Function]:
    return sorted((f for f in functions() if f.lines > MAX_LINES), key=lambda f: -f.lines)


def wide_functions() -> list[Function]:
    return sorted((f for f in functions() if f.positional > MAX_POSITIONAL),
                  key=lambda f: -f.positional)


def main() -> None:
    every = functions()
    print("ten longest functions:")
    for f in sorted(every, key=lambda f: -f.lines)[:10]:
        print(f"  {f.lines:>4} lines  {f.where}")
    print("ten widest (positional parameters):")
    for f in sorted(every, key=lambda f: -f.positional)[:10]:
        print(f"  {f.positional:>4}        {f.where}")
    longs, wides = long_functions(), wide_functions()
    print(f"functions over {MAX_LINES} lines: {len(longs)}")
    for f in longs:
        print(f"  {f.lines:>4}  {f.where}")
    print(f"functions with more than {MAX_POSITIONAL} positional parameters: {len(wides)}")
    for f in wides:
        print(f"  {f.positional:>4}  {f.where}")


if __name__ == "__main__":
    main()
