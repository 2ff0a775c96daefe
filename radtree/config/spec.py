"""The typing of one value: :class:`Spec` (kind, bounds, choices) and the field metadata.

A dataclass field's bounds, choices and TOML name (when it differs from the attribute:
``as_`` is written ``as``, ``direct_normal_table`` is written ``direct_normal``) are its
:func:`meta` metadata; :func:`spec_of` turns a field into the :class:`Spec` that the reader
(:mod:`radtree.config.reader`), the switch registry (:mod:`radtree.config.switches`) and the
dataclasses' own ``__post_init__`` (:class:`Checked`) check values with. An invalid value
raises :class:`SchemaError` (a :class:`radtree.errors.ConfigError`) naming the dotted field.
"""

from __future__ import annotations

import math
import re
from dataclasses import Field, dataclass, fields
from datetime import date as _date
from pathlib import Path
from typing import Any, ClassVar

from radtree.errors import ConfigError

TIME_RE = re.compile(r"^([01]\d|2[0-3]):([0-5]\d)$")


class SchemaError(ConfigError):
    """An invalid value; ``key`` is the dotted field, ``detail`` the message without place."""

    def __init__(self, detail: str, key: str):
        super().__init__(detail, field=key)
        self.detail, self.key = detail, key


def show(value: Any) -> str:
    """A value as the user wrote it (NumPy scalars as plain numbers, text quoted)."""
    if hasattr(value, "item") and not isinstance(value, str | bytes):
        try:
            value = value.item()
        except (TypeError, ValueError):
            pass
    return repr(value)


def _g(x: float) -> str:
    return f"{x:g}"


@dataclass(frozen=True)
class Spec:
    """What one value may be. ``kind``: ``float`` | ``int`` | ``bool`` | ``str`` | ``path`` |
    ``times`` (a list of ``HH:MM``) | ``date`` (``YYYY-MM-DD``) | ``mask`` ([cx, cy, r] px) |
    ``numbers`` (a non-empty list of numbers, each within the bounds) | ``rooms`` (``"all"`` or
    a list of ``"STOREY-BAY"`` names such as ``"0-1"``) | ``line`` ([[x1, y1], [x2, y2]], m).
    ``optional``: None is a value; ``path_ok``: a file path is accepted too (in the file)."""

    kind: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    choices: tuple[str, ...] | None = None
    optional: bool = False
    path_ok: bool = False
    hi_open: bool = False

    def expected(self) -> str:
        """What is expected, in words (for lists of keys and messages)."""
        words = {"float": "a number", "int": "an integer", "bool": "true or false",
                 "str": "text", "path": "a file path", "times": "a list of 'HH:MM' times",
                 "date": "a date YYYY-MM-DD", "mask": "[centre_x, centre_y, radius] in pixels",
                 "numbers": "a list of numbers", "rooms": "'all' or a list of 'STOREY-BAY' "
                 "names such as '0-1'", "line": "[[x1, y1], [x2, y2]] in metres"}
        text = words[self.kind]
        if self.choices:
            text = "one of " + ", ".join(self.choices)
        bounds = []
        if self.lo is not None:
            bounds.append(f"{'>' if self.lo_open else '≥'} {_g(self.lo)}")
        if self.hi is not None:
            bounds.append(f"{'<' if self.hi_open else '≤'} {_g(self.hi)}")
        if bounds:
            text += " " + " and ".join(bounds)
        if self.path_ok:
            text += " or a file path"
        return text

    def check(self, value: Any, *, lenient: bool = False, allow_path: bool = True) -> Any:
        """The value typed (int → float for a number; ``lenient``: a whole float is an integer),
        or ValueError with the message."""
        if hasattr(value, "item") and not isinstance(value, str | bytes | list | tuple):
            try:
                value = value.item()  # NumPy scalars
            except (TypeError, ValueError):
                pass
        if value is None and self.optional:
            return None
        if self.path_ok and allow_path and isinstance(value, str | Path):
            return self._path(value)
        k = self.kind
        if k == "float":
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"expected a number, got {show(value)}")
            value = float(value)
            if math.isnan(value) or math.isinf(value):
                raise ValueError(f"expected a finite number, got {value}")
            return self._bounds(value)
        if k == "int":
            whole = lenient and isinstance(value, float) and value.is_integer()
            if isinstance(value, bool) or not (isinstance(value, int) or whole):
                raise ValueError(f"expected an integer, got {show(value)}")
            return self._bounds(int(value))
        if k == "bool":
            if not isinstance(value, bool):
                raise ValueError(f"expected true or false, got {show(value)}")
            return value
        if k == "str":
            if not isinstance(value, str):
                raise ValueError(f"expected text, got {show(value)}")
            if self.choices is not None and value not in self.choices:
                raise ValueError(f"got {show(value)}, expected one of {', '.join(self.choices)}")
            return value
        if k == "path":
            return self._path(value)
        if k == "times":
            if not isinstance(value, list | tuple):
                raise ValueError(f"expected a list of 'HH:MM' times, got {show(value)}")
            for v in value:
                if not isinstance(v, str) or not TIME_RE.match(v):
                    raise ValueError(f"got {show(v)}, expected a local clock time HH:MM such "
                                     "as '10:30'")
            return tuple(value)
        if k == "date":
            try:
                _date.fromisoformat(value if isinstance(value, str) else "?")
            except ValueError:
                raise ValueError(f"got {show(value)}, expected YYYY-MM-DD") from None
            return value
        if k == "mask":
            if (not isinstance(value, list | tuple) or len(value) != 3 or not all(
                    isinstance(v, int | float) and not isinstance(v, bool) for v in value)):
                raise ValueError(f"expected [centre_x, centre_y, radius] in pixels, got "
                                 f"{show(value)}")
            return (float(value[0]), float(value[1]), float(value[2]))
        if k == "numbers":
            if not isinstance(value, list | tuple) or not value:
                raise ValueError(f"expected a non-empty list of numbers, got {show(value)}")
            return tuple(Spec("float", self.lo, self.hi, self.lo_open,
                              hi_open=self.hi_open).check(v) for v in value)
        if k == "rooms":
            return _rooms(value)
        if k == "line":
            return _line(value)
        raise ValueError(f"cannot check a value of kind {k!r}")  # pragma: no cover

    def _path(self, value: Any) -> Any:
        if isinstance(value, Path) or (isinstance(value, str) and value):
            return value
        raise ValueError(f"expected a file path, got {show(value)}")

    def _bounds(self, value: float) -> Any:
        lo, hi = self.lo, self.hi
        if lo is not None and (value < lo or (self.lo_open and value <= lo)):
            raise ValueError(f"got {value}, expected {'>' if self.lo_open else '≥'} {_g(lo)}")
        if hi is not None and (value > hi or (self.hi_open and value >= hi)):
            raise ValueError(f"got {value}, expected {'<' if self.hi_open else '≤'} {_g(hi)}")
        return value


ROOM_RE = re.compile(r"^(\d+)-(\d+)$")


def _rooms(value: Any) -> Any:
    """``"all"`` or a tuple of distinct ``"STOREY-BAY"`` names (ranges: the office's check)."""
    if value == "all":
        return value
    if not isinstance(value, list | tuple) or not value:
        raise ValueError(f"expected 'all' or a list of 'STOREY-BAY' names such as ['0-1', "
                         f"'1-1'], got {show(value)}")
    for v in value:
        if not isinstance(v, str) or not ROOM_RE.match(v):
            raise ValueError(f"got room {show(v)}, expected 'STOREY-BAY' such as '0-1' "
                             "(storey 0 = ground floor, bay 0 = leftmost seen from the street)")
    if len(set(value)) != len(value):
        raise ValueError(f"got {show(list(value))}: a room is named twice")
    return tuple(value)


def _line(value: Any) -> tuple[tuple[float, float], tuple[float, float]]:
    """Two distinct points [[x1, y1], [x2, y2]] (m)."""
    ok = (isinstance(value, list | tuple) and len(value) == 2 and all(
        isinstance(p, list | tuple) and len(p) == 2 and all(
            isinstance(c, int | float) and not isinstance(c, bool) and math.isfinite(c)
            for c in p) for p in value))
    if not ok:
        raise ValueError(f"expected [[x1, y1], [x2, y2]] in metres, got {show(value)}")
    (x1, y1), (x2, y2) = value
    if math.hypot(x2 - x1, y2 - y1) < 1e-6:
        raise ValueError(f"got {show(value)}: the two points coincide")
    return ((float(x1), float(y1)), (float(x2), float(y2)))


def line_azimuth(line: tuple[tuple[float, float], tuple[float, float]]) -> float:
    """Compass azimuth (degrees clockwise from north, 0–360) a façade along ``line`` looks
    towards: to the right of x1 → x2 (x east, y north)."""
    (x1, y1), (x2, y2) = line
    return math.degrees(math.atan2(y2 - y1, -(x2 - x1))) % 360.0


def meta(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False,
         hi_open: bool = False,
         choices: tuple[str, ...] | None = None, toml: str | None = None,
         kind: str | None = None, switch: bool = True, path_ok: bool = False) -> dict:
    """Field metadata: bounds, choices, the TOML name, the kind (else from the annotation),
    whether a scenario may switch it."""
    return {"lo": lo, "hi": hi, "lo_open": lo_open, "hi_open": hi_open, "choices": choices, "toml": toml,
            "kind": kind, "switch": switch, "path_ok": path_ok}


_KINDS = {"float": "float", "int": "int", "bool": "bool", "str": "str", "Path": "path"}


def table_fields(cls: type) -> list[Field]:
    """The fields a table of the project file holds: those of dataclass ``cls``, with the
    fields of its parameter groups (``cls.GROUPS``: attribute → dataclass, as
    :class:`radtree.config.engine.EngineParams`) in place of each group — the table stays
    flat in the file (``[engine] rays``) while the code holds ``params.numpy.rays``."""
    groups: dict[str, type] = getattr(cls, "GROUPS", {})
    out: list[Field] = []
    for f in fields(cls):
        out.extend(fields(groups[f.name]) if f.name in groups else (f,))
    return out


def table_field(cls: type, name: str) -> Field:
    """Field ``name`` of dataclass ``cls`` or of one of its groups (:func:`table_fields`)."""
    own = [f for f in fields(cls) if f.name == name]
    return own[0] if own else next(f for f in table_fields(cls) if f.name == name)


def spec_of(cls: type, name: str) -> Spec | None:
    """The :class:`Spec` of field ``name`` of dataclass ``cls`` (None: a nested table or a
    field the file does not hold); a field of one of its groups too (:func:`table_fields`)."""
    f = table_field(cls, name)
    m = dict(f.metadata) or meta()
    text = str(f.type)
    parts = [p.strip() for p in text.split("|")]
    optional = "None" in parts
    base = [p for p in parts if p != "None"][0]
    kind = m["kind"] or _KINDS.get(base)
    if kind is None or kind == "-":
        return None
    return Spec(kind, m["lo"], m["hi"], m["lo_open"], m["choices"], optional and kind != "path",
                m["path_ok"], m.get("hi_open", False))


def spec_for(cls: type, name: str) -> Spec:
    """:func:`spec_of` for a field known to have a Spec."""
    s = spec_of(cls, name)
    if s is None:
        raise TypeError(f"{cls.__name__}.{name} has no Spec")
    return s


def toml_name(cls: type, name: str) -> str:
    """The name a field of ``cls`` has in the project file (``as_`` → ``as``)."""
    f = table_field(cls, name)
    return dict(f.metadata).get("toml") or name


class Checked:
    """Validates every field with a :class:`Spec` on creation (numbers become floats)."""

    TABLE: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in fields(self):  # type: ignore[arg-type]
            s = spec_of(type(self), f.name)
            if s is None or s.kind in ("path", "times", "mask"):
                continue
            value = getattr(self, f.name)
            try:
                typed = s.check(value, lenient=True)
            except ValueError as exc:
                key = f"{self.TABLE}.{toml_name(type(self), f.name)}"
                raise SchemaError(str(exc), key) from None
            if typed is not value:
                object.__setattr__(self, f.name, typed)
        self.check()

    def check(self) -> None:
        """Rules across fields (none by default)."""

    def fail(self, name: str, detail: str) -> SchemaError:
        return SchemaError(detail, f"{self.TABLE}.{name}")
