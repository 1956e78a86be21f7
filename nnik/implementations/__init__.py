"""IK implementation families behind one interface (see :mod:`nnik.implementations.base`).

``FAMILIES`` maps a family name to its :class:`~nnik.implementations.base.Implementation`
subclass; families whose module is not importable are simply absent.
"""

from __future__ import annotations

import importlib

from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.problem import Problem

__all__ = ["FAMILIES", "Implementation", "IntRun", "Problem", "family"]

_MODULES = {"mlp": "mlp.family", "poly": "poly.family", "lut": "lut.family", "hybrid": "hybrid.family"}


def _load() -> dict[str, type[Implementation]]:
    out = {}
    for fam, mod in _MODULES.items():
        try:
            m = importlib.import_module(f"nnik.implementations.{mod}")
        except ModuleNotFoundError as exc:
            if exc.name not in (f"nnik.implementations.{mod}", f"nnik.implementations.{mod.partition('.')[0]}"):
                raise
            continue
        out[fam] = m.IMPLEMENTATION
    return out


FAMILIES: dict[str, type[Implementation]] = _load()


def family(name: str) -> type[Implementation]:
    from nnik.errors import NnikError

    if name not in FAMILIES:
        raise NnikError(f"unknown implementation family {name!r} (known: {', '.join(FAMILIES)})")
    return FAMILIES[name]
