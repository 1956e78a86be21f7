"""The shape of a JSON file nnik reads back (pick.json, metrics.json): a hand-edited value of the
wrong type is one line naming the file and the key, before anything uses it.

A shape is a type (NUM: an int or a float, never a bool; INT; STR; BOOL; ANY), a tuple of shapes
(any of them; None for JSON null), a list [shape] (every item), or a dict {key: shape} (the keys
nnik reads; a key starting with "?" may be absent; other keys are not checked)."""

from __future__ import annotations

import math
from typing import Any

from nnik.errors import NnikError


class NUM:
    """A JSON number, Infinity and NaN included (not a bool)."""


class FINITE:
    """A finite JSON number (not a bool)."""


class INT:
    """A JSON integer (not a bool)."""


class ANY:
    pass


STR, BOOL = str, bool
NAMES = {NUM: "a number", FINITE: "a finite number", INT: "an integer", STR: "a string", BOOL: "true or false", dict: "an object", list: "a list",
         None: "null"}


def _fits(v: Any, shape) -> bool:
    if shape is ANY:
        return True
    if shape is None:
        return v is None
    if shape in (NUM, FINITE):
        return isinstance(v, (int, float)) and not isinstance(v, bool) and (shape is NUM or math.isfinite(v))
    if shape is INT:
        return isinstance(v, int) and not isinstance(v, bool)
    if isinstance(shape, tuple):
        return any(_fits(v, s) for s in shape)
    if isinstance(shape, list):
        return isinstance(v, list)
    if isinstance(shape, dict):
        return isinstance(v, dict)
    return isinstance(v, shape)


def _name(shape) -> str:
    if isinstance(shape, tuple):
        return " or ".join(_name(s) for s in shape)
    if isinstance(shape, list):
        return "a list"
    if isinstance(shape, dict):
        return "an object"
    return NAMES.get(shape, getattr(shape, "__name__", str(shape)))


def _where(path: str) -> str:
    return path or "the top level"


def problem(v: Any, shape, path: str = "") -> str | None:
    """The first key whose value does not fit the shape, said in one line; None when all fit."""
    if not _fits(v, shape):
        got = "null" if v is None else type(v).__name__
        return f"{_where(path)}: expected {_name(shape)}, got {got} {str(v)[:40]!r}"
    if isinstance(shape, tuple):
        inner = next((s for s in shape if _fits(v, s)), None)
        return problem(v, inner, path) if isinstance(inner, (list, dict)) else None
    if isinstance(shape, list):
        for k, item in enumerate(v):
            p = problem(item, shape[0], f"{path}[{k}]")
            if p:
                return p
    if isinstance(shape, dict):
        for key, sub in shape.items():
            optional = key.startswith("?")
            key = key.lstrip("?")
            if key not in v:
                if not optional:
                    return f"{_where(path)}: missing key {key!r}"
                continue
            p = problem(v[key], sub, f"{path}.{key}" if path else key)
            if p:
                return p
    return None


def check(v: Any, shape, source: str, mend: str) -> None:
    """NnikError naming source and the key when v does not fit; `mend` says what rewrites it."""
    p = problem(v, shape)
    if p:
        raise NnikError(f"{p} (a hand-edited or foreign file?); {mend}", source)


# what nnik reads back of its own files
CHECK = {"?points": INT, "?mismatches": INT, "?bit_exact": BOOL, "?c_hash": STR, "?cycles": NUM, "?cycles_max": INT,
         "?flash_bytes": INT, "?ram_bytes": INT, "?not_run": STR, "?path": STR, "?compiler": STR,
         "?model_hash": (STR, None)}
TARGET = {"chip": STR, "max_error": FINITE, "?max_cycles": (FINITE, None), "?max_flash_bytes": (INT, None),
          "?max_error_source": STR}
PICK = {"version": INT, "name": STR, "?file": STR, "c_hash": STR, "family": STR, "config": dict,
        "?describe": (STR, None), "model_hash": (STR, None), "pre_max": FINITE, "target": TARGET,
        "?input_unit_um": FINITE, "?source": STR,
        "checks": {f"?{k}": CHECK for k in ("host", "avr", "avr_portable", "pic18", "pic18_portable")},
        "inputs": {"?model.pt": (STR, None), "?data.npz": (STR, None)}, "?selection": STR}
ERRORS = {"?max_abs": [NUM], "?rms": [NUM], "?p99": [NUM]}
ROW = {"family": STR, "?config": dict, "?picked": BOOL, "?describe": (STR, None), "?model_hash": (STR, None),
       "?c_hash": (STR, None), "?pre_max": NUM, "?cycles": dict, "?flash_bytes": dict, "?host": (dict, None),
       "?targets": dict}
METRICS = {
    "?name": STR, "?scenario": STR, "?unit": STR, "?outputs": [STR],
    "?network": {"?shape": [INT], "?mode": STR, "?normalize": BOOL, "?parameters": INT},
    "?dataset": {"?n_train": INT, "?n_val": INT, "?n_test": INT, "?truth": STR},
    "?float": ERRORS, "?affine_only": ERRORS,
    "?fixed": {**ERRORS, "?weights_bytes": INT, "?model_hash": STR, "?kernel": STR, "?weight_bits": INT},
    "?onnx": {"?max_abs_diff": NUM, "?tolerance": NUM, "?ok": BOOL},
    "?training": {"?stopped_by": STR, "?seconds": NUM}, "?train_seconds": NUM,
    "?tanh": {"?variant": STR, "?max_lsb": NUM, "?rms_lsb": NUM},
    "?host": CHECK, "?targets": {"?avr": CHECK, "?pic18": CHECK},
    "?selection": {"?target": TARGET, "?implementations": [ROW], "?ladder": [ROW],
                   "?pick": (None, {"?family": STR, "?config": dict, "?file": STR, "?model_hash": (STR, None)})},
}
