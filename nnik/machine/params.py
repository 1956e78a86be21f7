"""Typed, validated keys for TOML tables: every bad value becomes one clear NnikError line."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from nnik.errors import NnikError


@dataclass(frozen=True)
class Param:
    """One allowed key of a TOML table."""

    kind: str  # "float" | "int" | "str" | "bool" | "range" (two floats lo < hi) | "intlist" | "table"
    required: bool = False
    default: Any = None
    choices: tuple = ()
    check: Callable[[Any], str | None] | None = None  # returns a problem description or None
    doc: str = ""


def positive(v):
    return None if v > 0 else f"must be > 0, got {v}"


def non_negative(v):
    return None if v >= 0 else f"must be >= 0, got {v}"


MAX_LENGTH_MM = 100_000.0  # 100 m: no machine nnik serves is larger; beyond, int32 inputs and the C overflow


def within(lo: float, hi: float, open_lo: bool = False, unit: str = ""):
    """A check for a physical range: lo <= v <= hi (lo < v with open_lo)."""
    def check(v):
        ok = (v > lo if open_lo else v >= lo) and v <= hi
        return None if ok else f"must be in {'(' if open_lo else '['}{lo:g}, {hi:g}]{unit}, got {v:g}"
    return check


length_mm = within(0.0, MAX_LENGTH_MM, open_lo=True, unit=" mm")


def _coerce(value: Any, p: Param) -> Any:
    """Convert a TOML value to the declared kind, or return an error string."""
    if p.kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return TypeError(f"expected a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            return TypeError(f"must be a finite number, got {value!r}")
        return value
    if p.kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            return TypeError(f"expected an integer, got {value!r}")
        return value
    if p.kind == "str":
        if not isinstance(value, str):
            return TypeError(f"expected a string, got {value!r}")
        return value
    if p.kind == "bool":
        if not isinstance(value, bool):
            return TypeError(f"expected true or false, got {value!r}")
        return value
    if p.kind == "range":
        if not isinstance(value, list) or len(value) != 2:
            return TypeError(f"expected [min, max], got {value!r}")
        out = []
        for v in value:
            c = _coerce(v, Param("float"))
            if isinstance(c, Exception):
                return c
            out.append(c)
        if not out[0] < out[1]:
            return TypeError(f"min must be < max, got {value!r}")
        return (out[0], out[1])
    if p.kind == "intlist":
        if not isinstance(value, list) or not value:
            return TypeError(f"expected a non-empty list of integers, got {value!r}")
        if any(isinstance(v, bool) or not isinstance(v, int) or v <= 0 for v in value):
            return TypeError(f"expected positive integers, got {value!r}")
        return tuple(value)
    if p.kind == "table":
        if not isinstance(value, dict):
            return TypeError(f"expected a table, got {value!r}")
        return value
    raise AssertionError(p.kind)


def value_problem(value: Any, p: Param) -> tuple[Any, str | None]:
    """(the value as p's kind, None) or (None, the problem): the TOML key's one check, which the
    command line's options of the same meaning use too (nnik.commands.option_types)."""
    value = _coerce(value, p)
    if isinstance(value, Exception):
        return None, str(value)
    if p.choices and value not in p.choices:
        return None, f"must be one of {', '.join(map(str, p.choices))}; got {value!r}"
    problem = p.check(value) if p.check is not None else None
    return (None, problem) if problem else (value, None)


def validate_table(
    table: Any, schema: dict[str, Param], source: str, section: str, owner: str | None = None,
    also: tuple[str, ...] = (),
) -> dict[str, Any]:
    """Check a TOML table against its schema; returns the values with defaults filled in. ``also``
    names keys that another reader of the same table takes (listed as allowed in the error)."""
    where = f"[{section}]"
    if not isinstance(table, dict):
        raise NnikError(f"expected a table, got {table!r}", source, where)
    for key in table:
        if key not in schema:
            allowed = ", ".join(sorted((*schema, *also)))
            used_by = f" by {owner}" if owner else ""
            raise NnikError(f"unknown key (allowed{used_by}: {allowed})", source, f"{where} {key}")
    out: dict[str, Any] = {}
    for key, p in schema.items():
        if key not in table:
            if p.required:
                raise NnikError("missing required key", source, f"{where} {key}")
            out[key] = p.default
            continue
        value, problem = value_problem(table[key], p)
        if problem:
            raise NnikError(problem, source, f"{where} {key}")
        out[key] = value
    return out
