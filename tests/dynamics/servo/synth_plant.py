"""A plant nnik does not ship, for the identification tests: a first-order speed lag (K, tau) with
Coulomb friction and stiction as volts lost against the motion, integrated in substeps (the linear
part exactly per substep), read by an encoder that floors to whole counts, plus integer count noise.
"""

from __future__ import annotations

import math

import numpy as np


def simulate_counts(volts: np.ndarray, k: float, tau: float, tick: float, coulomb_v: float = 0.0,
                    stiction_v: float = 0.0, noise_counts: float = 0.0, substeps: int = 20, seed: int = 0,
                    p0: float = 0.0) -> np.ndarray:
    """Counts (N,) at each tick; volts[i] held from tick i to i + 1."""
    h = tick / substeps
    a = math.exp(-h / tau)
    rng = np.random.default_rng([seed, 0x5eed])  # never the excitation's stream (PCG64(seed))
    p, v = p0, 0.0
    out = np.empty(len(volts))
    for i, u in enumerate(volts):
        out[i] = p
        for _ in range(substeps):
            if v == 0.0 and abs(u) <= max(stiction_v, coulomb_v):
                continue  # stuck: friction holds the axis
            s = math.copysign(1.0, v) if v != 0.0 else math.copysign(1.0, u)
            ue = u - coulomb_v * s
            vn = a * v + k * (1 - a) * ue
            if v != 0.0 and vn * v < 0 and abs(u) <= max(stiction_v, coulomb_v):
                # the speed crosses zero inside the substep and friction can hold it: stop there
                frac = math.log((k * ue - 0.0) / (k * ue - v)) / math.log(a) if (k * ue - v) != 0 else 1.0
                frac = min(max(frac, 0.0), 1.0)
                p += k * ue * frac * h + (v - k * ue) * tau * (1 - a ** frac)
                v = 0.0
                continue
            p += k * ue * h + (v - k * ue) * tau * (1 - a)
            v = vn
    counts = np.floor(out)
    if noise_counts > 0:
        counts = counts + np.rint(rng.normal(0.0, noise_counts, len(out)))
    return counts


def log_rows(volts: np.ndarray, counts: np.ndarray, tick: float) -> str:
    n = len(volts)
    lines = ["t,u_x,u_y,count_x,count_y"]
    lines += [f"{i * tick:.6f},{volts[i, 0]:.6g},{volts[i, 1]:.6g},{counts[i, 0]:.0f},{counts[i, 1]:.0f}"
              for i in range(n)]
    return "\n".join(lines) + "\n"


def excitation_log(k: float, tau: float, amplitude: float, half_taus: float, coulomb_v: float = 0.0,
                   stiction_v: float = 0.0, noise_counts: float = 0.0, seed: int = 0, seconds: float = 20.0,
                   tick: float = 0.005, supply: float = 12.0, duty_max: int = 255):
    """A ServoLog of one plant (both axes alike but with different squares and noise): the seed's
    excitation played on it as `nnik excite` plays it."""
    from nnik.dynamics.servo.excitation import AxisExcitation, duties
    from nnik.dynamics.servo.log_csv import ServoLog

    n = int(round(seconds / tick))
    half = max(int(round(half_taus * tau / tick)), 4)
    d = duties((AxisExcitation(amplitude, half), AxisExcitation(amplitude, half + 7)), n, supply, duty_max, seed)
    volts = d / duty_max * supply
    counts = np.column_stack([simulate_counts(volts[:, i], k, tau, tick, coulomb_v, stiction_v, noise_counts,
                                              seed=seed + i) for i in range(2)])
    return ServoLog(np.arange(n) * tick, volts, counts, tick, d / duty_max)
