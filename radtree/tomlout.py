"""A small TOML writer for project data (what :mod:`tomllib` reads back, nothing more).

Handles tables, arrays of tables (``[[scenario]]``), arrays of scalars, text, integers, floats,
booleans and dates/times. Enough for a case's ``radtree.toml``; round-trips through tomllib.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import re
from typing import Any

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else json.dumps(k, ensure_ascii=False)


def _scalar(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        text = repr(v)
        return text if any(c in text for c in ".eE") else text + ".0"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, _dt.datetime | _dt.date | _dt.time):
        return v.isoformat()
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} {v!r} as TOML")


def _value(v: Any) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    return _scalar(v)


def _is_table_array(v: Any) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def _emit(table: dict[str, Any], path: list[str], lines: list[str]) -> None:
    simple = [(k, v) for k, v in table.items()
              if not isinstance(v, dict) and not _is_table_array(v)]
    for k, v in simple:
        lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in table.items():
        if isinstance(v, dict):
            sub = path + [k]
            lines.append("")
            lines.append("[" + ".".join(_key(p) for p in sub) + "]")
            _emit(v, sub, lines)
        elif _is_table_array(v):
            sub = path + [k]
            for item in v:
                lines.append("")
                lines.append("[[" + ".".join(_key(p) for p in sub) + "]]")
                _emit(item, sub, lines)


def dumps(data: dict[str, Any], header: str = "") -> str:
    """TOML text of ``data``; ``header`` lines become ``#`` comments at the top."""
    lines = [f"# {h}" if h else "#" for h in header.splitlines()]
    _emit(data, [], lines)
    return "\n".join(lines).lstrip("\n") + "\n"


def value_text(v: Any) -> str:
    """One TOML value (scalar, list or inline table) as text."""
    return _value(v)
