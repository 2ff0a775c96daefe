"""Sweep parameters and designs: full factorial and seeded Latin hypercube.

A parameter is a dotted project-file field (``tree.crown.trunk_distance_m``) with either

* a **range** ``a:b:n`` — n values spaced linearly from a to b (both included); a Latin
  hypercube samples the interval [a, b] and ignores n, so ``a:b`` is accepted there; or
* a **list** ``v1,v2,...`` — numbers, ``true``/``false`` or text (TOML scalars; anything that
  is not a TOML scalar is taken as text).

A design is an ordered list of cases, each a ``{field: value}`` mapping. Designs are pure data:
the same parameters, design kind, sample count and seed always give the same cases.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import tomllib

from radtree.errors import ConfigError

DESIGNS = ("full", "lhs")
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")
_NUMBER_RE = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_INT_RE = re.compile(r"^[+-]?\d+$")

Value = int | float | bool | str


def _tidy(v: float) -> float:
    """Round away binary noise of linspace/LHS arithmetic (12 significant digits)."""
    return float(f"{v:.12g}")


def parse_scalar(text: str) -> Value:
    """One value as a TOML scalar (``3``, ``2.5``, ``true``, ``"x"``), else the text itself."""
    t = text.strip()
    if not t:
        raise ConfigError("empty value")
    try:
        v = tomllib.loads(f"v = {t}")["v"]
    except tomllib.TOMLDecodeError:
        return t
    if isinstance(v, bool | int | float | str):
        return v
    return t  # dates, arrays, tables: keep the text


def parse_set(values: Iterable[str]) -> dict[str, object]:
    """``--set FIELD=VALUE`` options → {field: value}: a TOML list, else :func:`parse_scalar`."""
    out: dict[str, object] = {}
    for text in values:
        if "=" not in text:
            raise ConfigError(f"--set {text!r}: expected FIELD=VALUE, e.g. sensors.dense_grid=false")
        key, value = text.split("=", 1)
        v = value.strip()
        if v.startswith("["):
            try:
                out[key.strip()] = tomllib.loads(f"v = {v}")["v"]
            except tomllib.TOMLDecodeError as exc:
                raise ConfigError(f"--set {text!r}: not a TOML list ({exc})") from None
        else:
            out[key.strip()] = parse_scalar(v)
    return out


@dataclass(frozen=True)
class Parameter:
    """One swept field.

    ``kind`` is ``"range"`` (``low``, ``high`` and, for a full design, ``n``) or ``"list"``
    (``values``). ``integer`` marks an integer field (ranges then give whole numbers); it is set
    from the field's type by :func:`radtree.sweep.settings.resolve_parameters`.
    """

    name: str
    kind: str
    values: tuple[Value, ...] = ()
    low: float = math.nan
    high: float = math.nan
    n: int | None = None
    integer: bool = False
    text: str = ""

    def levels(self) -> list[Value]:
        """The values of a full factorial design (a range needs ``n``)."""
        if self.kind == "list":
            return list(self.values)
        if self.n is None:
            raise ConfigError(f"{self.name}={self.text}: a full factorial design needs the "
                              "number of values, write low:high:n (e.g. 2:6:5)", field=self.name)
        raw = np.linspace(self.low, self.high, self.n) if self.n > 1 else np.array([self.low])
        if self.integer:
            if not np.allclose(raw, np.round(raw)):
                raise ConfigError(
                    f"{self.name}={self.text}: this is an integer field but {self.n} values "
                    f"from {self.low:g} to {self.high:g} are not whole numbers "
                    f"({', '.join(f'{v:g}' for v in raw)})", field=self.name)
            return [int(round(v)) for v in raw]
        return [_tidy(float(v)) for v in raw]

    @property
    def numeric(self) -> bool:
        if self.kind == "range":
            return True
        return all(isinstance(v, int | float) and not isinstance(v, bool) for v in self.values)


def parse_param(text: str) -> Parameter:
    """Parse ``field=spec`` (the ``--param`` syntax)."""
    if "=" not in text:
        raise ConfigError(f"--param {text!r}: expected FIELD=VALUES, e.g. "
                          "tree.crown.trunk_distance_m=2:6:5 or tree.louvers.layers=3,4,5")
    name, spec = text.split("=", 1)
    return parse_spec(name.strip(), spec)


def parse_spec(name: str, spec: Any) -> Parameter:
    """A parameter from its field name and a spec: ``"a:b:n"``, ``"v1,v2"``, a list, a scalar."""
    if not _NAME_RE.match(name):
        raise ConfigError(f"{name!r} is not a dotted field name such as "
                          "tree.crown.trunk_distance_m", field=name)
    if isinstance(spec, list | tuple):
        if not spec:
            raise ConfigError("empty list of values", field=name)
        for v in spec:
            if not isinstance(v, bool | int | float | str):
                raise ConfigError(f"list values must be numbers, true/false or text, got {v!r}",
                                  field=name)
        return _list_param(name, tuple(spec), repr(list(spec)))
    if isinstance(spec, bool | int | float):
        return _list_param(name, (spec,), str(spec))
    if not isinstance(spec, str):
        raise ConfigError(f"expected 'low:high:n', 'v1,v2,...' or a list, got {spec!r}",
                          field=name)
    s = spec.strip()
    if not s:
        raise ConfigError("no values given (expected low:high:n or v1,v2,...)", field=name)
    parts = s.split(":")
    if len(parts) > 1 and _NUMBER_RE.match(parts[0].strip()):
        return _range_param(name, parts, s)
    items = [p for p in (x.strip() for x in s.split(","))]
    if any(not p for p in items):
        raise ConfigError(f"{name}={s}: empty item in the list of values", field=name)
    return _list_param(name, tuple(parse_scalar(p) for p in items), s)


def _list_param(name: str, values: tuple[Value, ...], text: str) -> Parameter:
    for v in values:
        if isinstance(v, float) and not math.isfinite(v):
            raise ConfigError(f"{name}={text}: values must be finite, got {v}", field=name)
    if len(set(map(repr, values))) != len(values):
        raise ConfigError(f"{name}={text}: values repeat", field=name)
    return Parameter(name=name, kind="list", values=values, text=text)


def _range_param(name: str, parts: list[str], text: str) -> Parameter:
    hint = "expected low:high:n (n values from low to high), e.g. 2:6:5, or low:high for lhs"
    if len(parts) not in (2, 3):
        raise ConfigError(f"{name}={text}: bad range, {hint}", field=name)
    a, b = parts[0].strip(), parts[1].strip()
    for p in (a, b):
        if not _NUMBER_RE.match(p):
            raise ConfigError(f"{name}={text}: range bound {p!r} is not a number; {hint}",
                              field=name)
    low, high = float(a), float(b)
    n = None
    if len(parts) == 3:
        c = parts[2].strip()
        if not _INT_RE.match(c) or int(c) < 1:
            raise ConfigError(f"{name}={text}: the number of values {c!r} must be a whole "
                              f"number ≥ 1; {hint}", field=name)
        n = int(c)
        if n > 1 and low == high:
            raise ConfigError(f"{name}={text}: low equals high, so {n} values would repeat",
                              field=name)
    if high < low:
        raise ConfigError(f"{name}={text}: high {high:g} is below low {low:g}", field=name)
    return Parameter(name=name, kind="range", low=low, high=high, n=n, text=text)


@dataclass(frozen=True)
class Design:
    """An ordered list of cases over ``parameters``."""

    kind: str
    parameters: tuple[Parameter, ...]
    cases: tuple[dict[str, Value], ...]
    seed: int | None = None
    notes: tuple[str, ...] = field(default=())

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    def __len__(self) -> int:
        return len(self.cases)


def _check_unique(parameters: Sequence[Parameter]) -> None:
    names = [p.name for p in parameters]
    if not names:
        raise ConfigError("no sweep parameters: give --param FIELD=VALUES (or a [sweep.params] "
                          "table in the project file)")
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ConfigError(f"parameter(s) given twice: {', '.join(dup)}")


def full_factorial(parameters: Sequence[Parameter]) -> Design:
    """Every combination; the last parameter varies fastest."""
    _check_unique(parameters)
    levels = [p.levels() for p in parameters]
    cases = tuple(dict(zip([p.name for p in parameters], combo, strict=True))
                  for combo in itertools.product(*levels))
    return Design("full", tuple(parameters), cases)


def latin_hypercube(parameters: Sequence[Parameter], samples: int, seed: int = 1) -> Design:
    """A Latin hypercube of ``samples`` cases, reproducible for a ``seed``.

    A continuous range [low, high] is cut into ``samples`` equal strata and each stratum holds
    exactly one case (uniform within it). An integer range is treated as the list of its whole
    numbers. A list (and an integer range) is stratified by value: each value is used
    ⌊samples/k⌋ or ⌈samples/k⌉ times. Columns are paired by independent random permutations.
    """
    _check_unique(parameters)
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ConfigError(f"the number of samples must be a whole number ≥ 1, got {samples!r}")
    rng = np.random.default_rng(seed)
    columns: dict[str, list[Value]] = {}
    notes = []
    for p in parameters:
        perm = rng.permutation(samples)
        if p.kind == "range" and not p.integer:
            u = (perm + rng.random(samples)) / samples
            columns[p.name] = [_tidy(p.low + float(x) * (p.high - p.low)) for x in u]
            if p.n is not None:
                notes.append(f"{p.name}: lhs samples the interval {p.low:g}–{p.high:g}; the "
                             f"count {p.n} in {p.text} is not used (--samples sets it)")
            continue
        if p.kind == "range":
            lo, hi = math.ceil(p.low), math.floor(p.high)
            if hi < lo:
                raise ConfigError(f"{p.name}={p.text}: no whole number in the range",
                                  field=p.name)
            values: list[Value] = list(range(lo, hi + 1))
        else:
            values = list(p.values)
        k = len(values)
        columns[p.name] = [values[int(i) * k // samples] for i in perm]
    names = [p.name for p in parameters]
    cases = tuple({n: columns[n][i] for n in names} for i in range(samples))
    return Design("lhs", tuple(parameters), cases, seed=seed, notes=tuple(notes))


def make_design(parameters: Sequence[Parameter], kind: str = "full",
                samples: int | None = None, seed: int = 1) -> Design:
    """``full`` factorial or ``lhs`` (``samples`` cases, default 10 per parameter)."""
    if kind not in DESIGNS:
        raise ConfigError(f"unknown design {kind!r} (expected one of {', '.join(DESIGNS)})")
    if kind == "full":
        d = full_factorial(parameters)
        if samples is not None:
            d = Design(d.kind, d.parameters, d.cases, None,
                       d.notes + (f"samples = {samples} is used only by lhs designs; the full "
                                  f"factorial has {len(d)} cases",))
        return d
    return latin_hypercube(parameters, samples if samples is not None else 10 * len(parameters),
                           seed)
