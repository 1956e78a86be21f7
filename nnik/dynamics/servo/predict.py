"""What an identified axis predicts for a log's volts: its counts at each sample, from the log's
first count and rest, by the speed model with the fitted Coulomb friction (its sign that of the
model's own simulated speed, as the output-error fit has it: nnik.dynamics.servo.output_error)."""

from __future__ import annotations

import numpy as np

from nnik.dynamics.servo.output_error import FRICTION_ROUNDS, increments_filter


def predict_increments(volts: np.ndarray, k: float, tau: float, coulomb_v: float, tick: float) -> np.ndarray:
    """(N,) the model's count increments dp[i] = p[i] - p[i-1] (dp[0] = 0)."""
    g = k * increments_filter(volts, tau, tick)
    dp = g
    for _ in range(FRICTION_ROUNDS if coulomb_v else 0):
        s = np.sign(np.concatenate([dp[1:], dp[-1:]]))
        dp = g - k * coulomb_v * increments_filter(s, tau, tick)
    return dp


def predict_counts(volts: np.ndarray, p0: float, k: float, tau: float, coulomb_v: float, tick: float) -> np.ndarray:
    return p0 + np.cumsum(predict_increments(volts, k, tau, coulomb_v, tick))
