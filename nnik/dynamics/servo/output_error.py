"""The output-error fit of the speed model: K, tau and Coulomb friction minimising the squared
difference between the measured count increments and the model's own simulated ones.

Why not the seed's least squares alone: equation-error least squares (RLS and its batch check,
nnik.dynamics.servo.rls / batch_ls) regresses dp[k] on the measured dp[k-1], and an encoder's
quantisation and count noise sit in that regressor; the estimate of the pole a is biased toward 0
and tau comes out short. Measured on a first-order plant with only the encoder's floor to whole
counts (K 389 counts/s/V, tau 0.286 s, 6 V square plus the seed's noise): tau 0.194 s by least
squares. The simulated increments carry no measurement noise, so the output-error fit is
consistent.

The model, for a tau (a = exp(-T / tau)), is linear in the rest:

    dp_sim = K * G_tau(u) - K * Uc * G_tau(s) + d0 * a^k,

G_tau the speed model's exact ZOH increment filter (nnik.dynamics.servo.speed_model), s the sign
of the motion, d0 the speed the log starts with. So for each tau the rest is a linear least
squares solve, and tau is found by a log-spaced grid (TAU_GRID points between 0.5 tick and
MAX_TAU_TICKS ticks) refined by a bounded scalar search (variable projection). s is the sign of
the model's own simulated speed (starting from the fit without friction; FRICTION_ROUNDS rounds),
never of the noisy measured one. Friction only opposes the motion: a fit that gives it the
other sign (noise can) is replaced by the fit without it.

The covariance (for the confidence intervals) is the HAC sandwich (nnik.dynamics.servo.batch_ls)
on the residuals with the Jacobian in (tau, K, K*Uc, d0), taken by central differences in tau.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import lfilter

from nnik.dynamics.servo.batch_ls import hac_covariance

TAU_GRID = 48
MAX_TAU_TICKS = 2000  # 10 s at 5 ms
FRICTION_ROUNDS = 3


@dataclass(frozen=True)
class OeFit:
    k: float
    tau: float
    coulomb_v: float
    cov: np.ndarray  # (4, 4) over (tau, K, K*Uc, d0)
    residuals: np.ndarray
    speed_fit: float  # 1 - |residual| / |dp - mean|: 1 is a perfect fit


def increments_filter(u: np.ndarray, tau: float, tick: float) -> np.ndarray:
    """The model's count increments dp[k] = p[k] - p[k-1] for K = 1 from rest: G_tau(u)."""
    a = math.exp(-tick / tau)
    b1, b0 = tick - tau * (1 - a), tau * (1 - a) - a * tick
    return lfilter([0.0, b1, b0], [1.0, -a], u)


def _design(u, s, tau, tick, friction: bool) -> np.ndarray:
    a = math.exp(-tick / tau)
    cols = [increments_filter(u, tau, tick)]
    if friction:
        cols.append(-increments_filter(s, tau, tick))
    cols.append(a ** np.arange(len(u), dtype=float))
    return np.column_stack(cols)


def _solve(dp, u, s, tau, tick, friction):
    x = _design(u, s, tau, tick, friction)
    beta, *_ = np.linalg.lstsq(x, dp, rcond=None)
    r = dp - x @ beta
    return float(r @ r), beta, x


def tau_bounds(tick: float) -> tuple[float, float]:
    """The range tau is searched in (s)."""
    return 0.5 * tick, MAX_TAU_TICKS * tick


def _best_tau(dp, u, s, tick, friction) -> float:
    grid = np.geomspace(*tau_bounds(tick), TAU_GRID)
    cost = [_solve(dp, u, s, t, tick, friction)[0] for t in grid]
    i = int(np.argmin(cost))
    lo, hi = math.log(grid[max(i - 1, 0)]), math.log(grid[min(i + 1, len(grid) - 1)])
    res = minimize_scalar(lambda lt: _solve(dp, u, s, math.exp(lt), tick, friction)[0], bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-6})
    return math.exp(res.x)


def fit_output_error(dp: np.ndarray, u: np.ndarray, tick: float) -> OeFit:
    """dp (N,) measured increments (dp[0] = 0), u (N,) volts held from each sample to the next.
    Friction only opposes motion: a fit that gives it the other sign is replaced by the fit
    without it (Coulomb 0)."""
    zero = np.zeros_like(u)
    tau0 = _best_tau(dp, u, zero, tick, False)
    s, tau = zero, tau0
    for _ in range(FRICTION_ROUNDS):
        _, beta, x = _solve(dp, u, s, tau, tick, True)
        sim = x @ beta
        s = np.sign(np.concatenate([sim[1:], sim[-1:]]))  # the speed's sign while u[k] acts
        tau = _best_tau(dp, u, s, tick, True)
    _, beta, x = _solve(dp, u, s, tau, tick, True)
    if not beta[1] * beta[0] > 0:  # no friction, or friction that pushes: the linear fit
        s, tau = zero, tau0
        _, beta, x = _solve(dp, u, s, tau, tick, True)
    r = dp - x @ beta
    h = 1e-4 * tau
    dx = (_design(u, s, tau + h, tick, True) - _design(u, s, tau - h, tick, True)) / (2 * h)
    jac = np.column_stack([dx @ beta, x])
    if not s.any():
        jac = np.delete(jac, 2, axis=1)  # the friction column is all zero
        beta = np.insert(beta, 1, 0.0)
    cov = hac_covariance(jac, r)
    k = float(beta[0])
    uc = float(beta[1] / beta[0]) if beta[0] != 0 else math.nan
    spread = float(np.linalg.norm(dp - dp.mean()))
    fit = 1.0 - float(np.linalg.norm(r)) / spread if spread > 0 else 0.0
    return OeFit(k, tau, uc, cov, r, fit)
