"""The encoder on the motor shaft: quadrature 4x counts, or the seed's 8-bit counters.

count = floor(motor angle / 2 pi * counts per motor turn): the count changes at each edge the
decoder sees. In "counter8" mode the chip reads only the low 8 bits (raw8 = count mod 256) and
unwraps each reading against the previous one by the shortest way round,

    unwrapped = previous + ((raw8 - previous_raw8 + 128) mod 256) - 128,

which is the true count while the axis moves less than 128 counts between readings (the scenario
check refuses a plant whose full speed breaks that at the tick).
"""

from __future__ import annotations

import numpy as np


def counts(angle_rad: np.ndarray, counts_per_motor_rev: float) -> np.ndarray:
    return np.floor(angle_rad * (counts_per_motor_rev / (2 * np.pi))).astype(np.int64)


def raw8(count) -> np.ndarray | int:
    return np.bitwise_and(count, 0xFF)


def unwrap8(previous: int, readings: np.ndarray) -> np.ndarray:
    """Each 8-bit reading unwrapped against `previous` (an unwrapped count), as the chip does when
    it reads once: every row of a tick is read against the count at the tick's start."""
    delta = (np.asarray(readings, dtype=np.int64) - (previous & 0xFF) + 128) % 256 - 128
    return previous + delta
