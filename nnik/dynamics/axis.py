"""One axis of a belt machine as seed 003 models it: a base-excited spring-damper.

The motor puts the base (the belt's driven end); the tip (the tool) follows through
    tip'' = wn^2 (base - tip) + 2 zeta wn (base' - tip'),
i.e. the transfer function (2 zeta wn s + wn^2) / (s^2 + 2 zeta wn s + wn^2), written here in
state space (controllable form: x' = A x + B base, tip = C x).  Steps make the base piecewise
constant, so a zero-order hold over each interval is exact: the discrete system is the matrix
exponential of [[A, B], [0, 0]] dt (scipy.signal.cont2discrete, method "zoh"), not Euler.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.signal import lfilter, lfilter_zi, ss2tf


def wn(f_hz: float) -> float:
    return 2.0 * math.pi * f_hz


def state_space(f_hz: float, zeta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    w = wn(f_hz)
    a = np.array([[0.0, 1.0], [-w * w, -2.0 * zeta * w]])
    b = np.array([[0.0], [1.0]])
    c = np.array([[w * w, 2.0 * zeta * w]])
    return a, b, c, np.zeros((1, 1))


def discrete(f_hz: float, zeta: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Ad, Bd, C): the exact zero-order-hold discretisation over dt, by the matrix exponential."""
    a, b, c, _ = state_space(f_hz, zeta)
    m = np.zeros((3, 3))
    m[:2, :2], m[:2, 2:] = a, b
    e = expm(m * dt)
    return e[:2, :2], e[:2, 2:], c


def tip(base: np.ndarray, dt: float, f_hz: float, zeta: float) -> np.ndarray:
    """The tip at each sample of a base held constant over each dt interval (base[k] over
    [k dt, (k+1) dt)); the machine starts at rest at base[0].  tip[k] is the tip at time k dt."""
    base = np.asarray(base, dtype=float)
    if base.size == 0:
        return base.copy()
    ad, bd, c = discrete(f_hz, zeta, dt)
    num, den = ss2tf(ad, bd, c, np.zeros((1, 1)))
    num = num[0]
    # no feedthrough: num[0] = 0, so out[k] follows the input up to k - 1, the tip at k dt
    zi = lfilter_zi(num, den) * base[0]
    out, _ = lfilter(num, den, base, zi=zi)
    return out


def tip_xy(base_xy: np.ndarray, dt: float, f_hz: tuple[float, float], zeta: tuple[float, float]) -> np.ndarray:
    """tip() per Cartesian axis of an (N, 2) base."""
    return np.stack([tip(base_xy[:, i], dt, f_hz[i], zeta[i]) for i in range(2)], axis=1)


def static_lag(accel: float, f_hz: float) -> float:
    """The tip's lag behind the base under a steady acceleration: a / wn^2 (the base-excited
    model's damping term adds a velocity lead that cancels its velocity lag at steady speed)."""
    return accel / wn(f_hz) ** 2
