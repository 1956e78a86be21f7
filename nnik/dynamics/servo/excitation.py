"""The seed's excitation: a square wave plus Gaussian noise on each axis, both axes at once.

The seed gives the noise's "variance 30 % of the square's amplitude"; nnik reads it literally:
sigma^2 = 0.3 * A with A the square's amplitude in volts (A = 6 V gives sigma = 1.34 V).

Each axis's square starts with a half-length segment (+A for a quarter period, then -A for a half,
+A for a half, ...), so the position it drives oscillates around where the axis started instead of
walking off one way: the table starts at the middle of its stroke and stays near it. The volts are
quantised to the integer duty (round(volts / supply * duty_max)) and clamped to +-duty_max, as the
chip applies them; the noise comes from numpy's PCG64 with the given seed, so a seed gives the
same duties on every machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

NOISE_VARIANCE_PER_VOLT = 0.3  # sigma^2 = 0.3 * A (V^2 per V of amplitude): the seed, read literally


@dataclass(frozen=True)
class AxisExcitation:
    amplitude_v: float  # A, the square's amplitude
    half_period_ticks: int  # the square's half period

    @property
    def sigma_v(self) -> float:
        return math.sqrt(NOISE_VARIANCE_PER_VOLT * self.amplitude_v)


def square(n: int, half: int) -> np.ndarray:
    """+-1, starting with a half-length (quarter-period) segment of +1."""
    k = np.arange(n) + half // 2
    return np.where((k // half) % 2 == 0, 1.0, -1.0)


def duties(axes: tuple[AxisExcitation, AxisExcitation], n: int, supply_v: float, duty_max: int,
           seed: int) -> np.ndarray:
    """(n, 2) int duties of the excitation on both axes (x's noise drawn first, then y's)."""
    rng = np.random.Generator(np.random.PCG64(seed))
    out = np.empty((n, 2), dtype=np.int64)
    for i, ax in enumerate(axes):
        volts = ax.amplitude_v * square(n, ax.half_period_ticks) + ax.sigma_v * rng.standard_normal(n)
        out[:, i] = np.clip(np.rint(volts / supply_v * duty_max), -duty_max, duty_max).astype(np.int64)
    return out
