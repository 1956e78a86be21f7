"""The identified model of one DC-servo axis: speed (counts/s) = K * volts through a first-order
lag tau; position (counts) is the speed's integral.

    tau * dv/dt + v = K * u,     dp/dt = v

With the volts held over each tick T (zero-order hold), the exact discretisation is, with
a = exp(-T / tau):

    v[k+1] = a v[k] + K (1 - a) u[k]
    p[k+1] = p[k] + tau (1 - a) v[k] + K (T - tau (1 - a)) u[k]

and the position transfer function from volts to counts is

    P(z) / U(z) = (b1 z + b0) / ((z - 1)(z - a)),
    b1 = K (T - tau (1 - a)),   b0 = K (tau (1 - a) - a T),   b1 + b0 = K T (1 - a).

In increments dp[k] = p[k] - p[k-1] (what nnik identify fits) the same model reads
dp[k] = a dp[k-1] + b1 u[k-1] + b0 u[k-2].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nnik.dynamics.servo.servo_error import ServoError


@dataclass(frozen=True)
class DiscreteModel:
    """The position transfer function of a SpeedModel at one tick: num / den in powers of z
    (num = (b1, b0), den = (1, -(1 + a), a)); `a` is the speed's pole."""

    tick_s: float
    a: float
    b1: float
    b0: float

    @property
    def num(self) -> tuple[float, float]:
        return (self.b1, self.b0)

    @property
    def den(self) -> tuple[float, float, float]:
        return (1.0, -(1.0 + self.a), self.a)

    def describe(self) -> str:
        """The transfer function as one line of text (z-domain, volts to counts)."""
        return (f"P(z)/U(z) = ({self.b1:.6g} z + {self.b0:.6g}) / (z^2 - {1.0 + self.a:.6g} z + {self.a:.6g})"
                f"  [T = {self.tick_s:g} s]")


@dataclass(frozen=True)
class SpeedModel:
    """K in counts/s per volt, tau in s; k_ci and tau_ci the 95 % confidence intervals (lo, hi) when
    the model was identified (None for a model given by hand)."""

    k_counts_s_v: float
    tau_s: float
    k_ci: tuple[float, float] | None = None
    tau_ci: tuple[float, float] | None = None

    def __post_init__(self):
        if not (math.isfinite(self.k_counts_s_v) and self.k_counts_s_v > 0):
            raise ServoError(f"speed model: K must be a positive number of counts/s/V, not {self.k_counts_s_v!r}")
        if not (math.isfinite(self.tau_s) and self.tau_s > 0):
            raise ServoError(f"speed model: tau must be a positive number of seconds, not {self.tau_s!r}")

    def discrete(self, tick_s: float) -> DiscreteModel:
        """The exact (zero-order hold) discretisation at tick_s: the position transfer function."""
        if not (math.isfinite(tick_s) and tick_s > 0):
            raise ServoError(f"speed model: the tick must be a positive number of seconds, not {tick_s!r}")
        a = math.exp(-tick_s / self.tau_s)
        k, tau = self.k_counts_s_v, self.tau_s
        return DiscreteModel(tick_s, a, k * (tick_s - tau * (1.0 - a)), k * (tau * (1.0 - a) - a * tick_s))

    def simulate(self, volts, tick_s: float, p0: float = 0.0, v0: float = 0.0) -> np.ndarray:
        """The model's counts at each tick: counts[0] = p0, and volts[k] is held from tick k to k + 1,
        so counts[k] depends on volts[:k] only (volts[-1] moves nothing that is returned). v0 is the
        speed at tick 0 in counts/s."""
        u = np.asarray(volts, dtype=float).reshape(-1)
        d = self.discrete(tick_s)
        a, tau, k = d.a, self.tau_s, self.k_counts_s_v
        gv, gp = k * (1.0 - a), d.b1  # volts -> speed, volts -> position over one tick
        cp = tau * (1.0 - a)  # speed -> position over one tick
        out = np.empty(len(u))
        p, v = float(p0), float(v0)
        for i, ui in enumerate(u):
            out[i] = p
            p, v = p + cp * v + gp * ui, a * v + gv * ui
        return out

    def scenario_lines(self, axis: str) -> str:
        """The model as the scenario's [servo.<axis>.identified] table."""
        return (f"[servo.{axis}.identified]\n"
                f"k_counts_s_v = {self.k_counts_s_v:.6g}\n"
                f"tau_s = {self.tau_s:.6g}\n")
