"""The document model of the report: cells, tables, figures, sections, and number formatting."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

# Decimals per kind of number (fixed, so tests and eyes can compare).
D_UNIT = 4  # errors in microsteps / LSB
D_DEG = 5  # errors in degrees
D_UM = 2  # micrometres
D_PCT = 4  # relative errors, %
D_LSB = 3  # tanh errors in LSB of Q15
D_CYC = 0  # cycles, bytes
D_US = 1  # microseconds
D_MS = 2  # milliseconds
D_DIFF = 1  # estimate vs measured, %
D_SEC = 1  # seconds


@dataclass
class Cell:
    text: str
    value: float | int | None = None  # raw number -> data-value
    key: str | None = None  # place in metrics.json -> data-key
    cls: str = ""
    colspan: int = 1
    rowspan: int = 1
    title: str = ""

    @property
    def data_value(self) -> str | None:
        if self.value is None:
            return None
        if isinstance(self.value, (bool, np.bool_)):
            return str(bool(self.value)).lower()
        if isinstance(self.value, (int, np.integer)):
            return str(int(self.value))
        return repr(float(self.value))


@dataclass
class Table:
    id: str
    title: str
    header: list[str]
    rows: list[list[Cell]] = field(default_factory=list)
    note: str = ""


@dataclass
class Fig:
    file: str
    alt: str
    caption: str


@dataclass
class Section:
    id: str
    title: str
    paragraphs: list[str] = field(default_factory=list)
    not_run: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Fig] = field(default_factory=list)
    verdicts: list[tuple[str, str]] = field(default_factory=list)  # (cls "good"|"bad"|"info", text)
    figures_first: bool = False  # the pictures above the paragraphs and tables (a section led by its figure)


def finite(v) -> bool:
    try:
        return v is not None and not isinstance(v, bool) and math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def fmt(v, digits: int | str) -> str:
    """A number with a fixed number of decimals ("sci" for scientific); '—' when absent."""
    if not finite(v):
        return "—" if v is None else str(v)
    if digits == "sci":
        return f"{float(v):.2e}"
    return f"{float(v):.{int(digits)}f}"


def num(v, digits: int | str, key: str | None = None, cls: str = "num", title: str = "") -> Cell:
    if not finite(v):
        return Cell("—", cls="num missing", title=title)
    return Cell(fmt(v, digits), value=v, key=key, cls=cls, title=title)


def txt(s: Any, cls: str = "", colspan: int = 1, rowspan: int = 1, title: str = "") -> Cell:
    return Cell("—" if s is None else str(s), cls=cls, colspan=colspan, rowspan=rowspan, title=title)


def not_run_cell(reason: str, colspan: int) -> Cell:
    return Cell(f"not run — {reason}", cls="notrun", colspan=colspan)


def lookup(d: Any, *path, default=None):
    for p in path:
        if isinstance(d, dict) and p in d:
            d = d[p]
        elif isinstance(d, list) and isinstance(p, int) and -len(d) <= p < len(d):
            d = d[p]
        else:
            return default
    return d


def keypath(*path) -> str:
    return "/".join(str(p) for p in path)
