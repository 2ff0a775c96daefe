"""The shape of the code: layers (DESIGN.md, the import-linter contract in pyproject.toml), no
import cycles, small modules, engine names only inside ``engines/`` and the CLI."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import grimp

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "radtree"
MAX_LINES = 500


def _cycles(adj: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in sorted(adj):
        if root in index:
            continue
        work = [(root, iter(sorted(adj[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(adj.get(w, ())))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    x = stack.pop()
                    on.discard(x)
                    comp.append(x)
                    if x == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    """Every import counts, including those inside functions."""
    graph = grimp.build_graph("radtree")
    adj = {m: set(graph.find_modules_directly_imported_by(m)) for m in graph.modules}
    assert _cycles(adj) == []


def test_layers_contract_holds():
    """``lint-imports`` (import-linter) keeps the layers of pyproject.toml."""
    exe = Path(sys.executable).with_name("lint-imports")
    done = subprocess.run([str(exe)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]


def test_modules_are_small():
    big = {str(p.relative_to(ROOT)): n for p in PACKAGE.rglob("*.py")
           if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert big == {}


#: the ratchet (issue 42): at most this many functions over ``tests.shape.MAX_LINES`` lines and
#: with more than ``tests.shape.MAX_POSITIONAL`` positional parameters. Lower the figures when a
#: change shortens the lists (``python -m tests.shape`` prints them); never raise them.
MAX_LONG_FUNCTIONS = 0
MAX_WIDE_FUNCTIONS = 0


def test_function_ratchet():
    from tests.shape import long_functions, wide_functions

    longs, wides = long_functions(), wide_functions()
    assert len(longs) <= MAX_LONG_FUNCTIONS, [f"{f.where} ({f.lines} lines)" for f in longs]
    assert len(wides) <= MAX_WIDE_FUNCTIONS, [f"{f.where} ({f.positional})" for f in wides]


def test_shape_counts_what_it_says(tmp_path):
    from tests.shape import functions

    pkg = tmp_path / "radtree"
    pkg.mkdir()
    body = "\n".join(f"    x{i} = {i}" for i in range(85))
    (pkg / "m.py").write_text(f"class C:\n    def wide(self, a, b, c, d, e, f, g, h, i, *, j):\n"
                              f"        return a\n\ndef long():\n{body}\n", encoding="utf-8")
    got = {f.where: (f.lines, f.positional) for f in functions(pkg)}
    assert got == {"radtree/m.py:C.wide": (2, 9), "radtree/m.py:long": (86, 0)}


def _engine_name_pattern(names: list[str]) -> re.Pattern[str]:
    """A comparison with, an assignment of, or a tuple of quoted engine names."""
    name = rf"""["'](?:{'|'.join(map(re.escape, names))})["']"""
    return re.compile(rf"(?:==|!=|=)\s*{name}|{name}\s*(?:==|!=|\bin\b)|{name}\s*,\s*{name}")


def test_engine_name_pattern_catches_comparisons():
    pattern = _engine_name_pattern(["forward", "numpy"])
    assert pattern.search('if t["engine"] == "forward":')
    assert pattern.search("keep = 'numpy' != e")
    assert pattern.search('engines=("forward", "numpy")')
    assert not pattern.search('Variant("study", {}, "forward", "the method")')
    assert not pattern.search('engine = "radiance"')


def test_engine_names_only_in_engines_and_cli():
    """No ``== "radiance"`` / ``"numpy"`` / ``"forward"`` branches above the engine interface:
    every name of the engine registry is checked (a capability on the engine class —
    ``photon_budget``, ``seeded``, ``uses_build_folder`` — says what a caller needs)."""
    from radtree.engines.registry import ENGINES

    assert {"radiance", "numpy", "forward"} <= set(ENGINES)
    pattern = _engine_name_pattern(sorted(ENGINES))
    offenders = []
    for p in PACKAGE.rglob("*.py"):
        rel = p.relative_to(PACKAGE).as_posix()
        if rel.startswith(("engines/", "cli/")):
            continue
        for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#", 1)[0]
            if pattern.search(code):
                offenders.append(f"{rel}:{i}: {line.strip()}")
    assert offenders == []
