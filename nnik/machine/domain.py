"""The trained input domain in integer micrometres, as every generated C function clamps it."""

from __future__ import annotations

import numpy as np

from nnik.machine.kinematics.base import Workspace


def domain_um(ws: Workspace) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) int64 per input axis: the workspace rounded inward to whole micrometres."""
    lo = np.ceil(np.round(ws.lo * 1000, 6)).astype(np.int64)
    hi = np.floor(np.round(ws.hi * 1000, 6)).astype(np.int64)
    return lo, hi


def clamp_um(in_um: np.ndarray, ws: Workspace) -> tuple[np.ndarray, np.ndarray]:
    """Clamp (N, 2) int64 inputs to the domain -> (clamped inputs, flag (N,) int64: 1 if any clamped)."""
    lo, hi = domain_um(ws)
    c = np.clip(in_um.astype(np.int64), lo, hi)
    return c, np.any(c != in_um, axis=1).astype(np.int64)


def round_half_up_shift(v: np.ndarray, shift: int) -> np.ndarray:
    """C's (v + (1 << (shift-1))) >> shift on int64 arrays (arithmetic shift), shift >= 1."""
    return (v + (np.int64(1) << (shift - 1))) >> shift
