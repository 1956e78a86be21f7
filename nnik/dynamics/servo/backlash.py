"""Gearbox backlash as a play (dead-band) operator: the table, massless in the play, moves only
when the gearbox output pushes it from one side of the gap or the other.

    table[k] = clip(table[k-1], motor[k] - play/2, motor[k] + play/2)

sampled at the plant's substep ends. For a monotonic run of motor positions the sequential clip
equals one clip against each sample's own band (the lower bounds only rise on the way up, the upper
only fall on the way down), which is how a tick without a reversal is done at once.
"""

from __future__ import annotations

import numpy as np


def play(table0: float, motor_prev: float, motor: np.ndarray, backlash: float) -> np.ndarray:
    """The table's positions after each of `motor`'s samples (same unit), from table0 with the
    previous motor sample motor_prev; backlash 0 is a rigid drive (table = motor)."""
    if backlash <= 0:
        return motor.copy()
    half = backlash / 2
    d = np.diff(motor, prepend=motor_prev)
    if (d >= 0).all() or (d <= 0).all():
        return np.clip(table0, motor - half, motor + half)
    out = np.empty_like(motor)
    t = table0
    for k, m in enumerate(motor):
        t = min(max(t, m - half), m + half)
        out[k] = t
    return out
