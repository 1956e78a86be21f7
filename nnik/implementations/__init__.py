"""IK implementation families behind one interface (see :mod:`nnik.implementations.base`).

``FAMILIES`` maps a family name to its :class:`~nnik.implementations.base.Implementation`
subclass, loaded from ``REGISTRY``; families whose folder is absent are simply not offered.
Each family is one folder (``mlp/``, ``poly/``, ``lut/``, ``hybrid/``) whose ``family.py``
defines ``IMPLEMENTATION``; the rest of the folder is its fit, integer model, C, fast paths, cost
and calibration.
"""

from __future__ import annotations

import importlib

from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.problem import Problem

__all__ = ["FAMILIES", "REGISTRY", "Implementation", "IntRun", "Problem", "family", "load_family"]

# The registry: family name -> the module that holds its IMPLEMENTATION (an Implementation
# subclass). Adding a family is one folder under nnik/implementations/ and one line here
# (docs/families.md, "Adding a family").
REGISTRY = {
    "mlp": "nnik.implementations.mlp.family",
    "poly": "nnik.implementations.poly.family",
    "lut": "nnik.implementations.lut.family",
    "hybrid": "nnik.implementations.hybrid.family",
}


def load_family(module: str) -> type[Implementation]:
    """The Implementation subclass a family module registers as IMPLEMENTATION."""
    cls = importlib.import_module(module).IMPLEMENTATION
    if not (isinstance(cls, type) and issubclass(cls, Implementation)):
        raise TypeError(f"{module}.IMPLEMENTATION is not an Implementation subclass")
    return cls


def _load() -> dict[str, type[Implementation]]:
    out = {}
    for fam, mod in REGISTRY.items():
        try:
            out[fam] = load_family(mod)
        except ModuleNotFoundError as exc:  # a family whose folder is absent is simply not offered
            if exc.name not in (mod, mod.rpartition(".")[0]):
                raise
            continue
        if out[fam].family != fam:
            raise TypeError(f"{mod}: registered as {fam!r} but its family is {out[fam].family!r}")
    return out


FAMILIES: dict[str, type[Implementation]] = _load()


def family(name: str) -> type[Implementation]:
    from nnik.errors import NnikError

    if name not in FAMILIES:
        raise NnikError(f"unknown implementation family {name!r} (known: {', '.join(FAMILIES)})")
    return FAMILIES[name]
