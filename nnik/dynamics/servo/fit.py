"""One axis's speed model fitted to a log.

Two fits, both reported:
- The seed's method: the discrete model on count increments dp[k] = p[k] - p[k-1] (u[k] held from
  sample k to k + 1), exactly the speed model's position transfer function
  (b1 z + b0) / ((z - 1)(z - a)) written on increments so the integrator's unknown start drops out,

      dp[k] = a dp[k-1] + b1 u[k-1] + b0 u[k-2],

  fitted by recursive least squares (nnik.dynamics.servo.rls) and checked by batch least squares
  (nnik.dynamics.servo.batch_ls): the two must agree (RLS_AGREEMENT), else the log is refused.
  tau = -T / ln a and K = (b1 + b0) / (T (1 - a)).
- nnik's K and tau (the model that is written and used): the output-error fit
  (nnik.dynamics.servo.output_error), which also fits Coulomb friction as volts lost against the
  motion. Equation-error least squares is biased by the encoder's quantisation and count noise
  (output_error's docstring gives the measured case); the output-error fit is not.

Confidence intervals, 95 % (normal quantile 1.96): estimate +- 1.96 standard errors, from the
output-error fit's HAC (Newey-West) covariance. They say how well the log pins the model down, not
how well a first-order model fits a plant with stiction or backlash (speed_fit says that).

Per axis the log is refused (ServoError, one line) when the input never changes (no excitation),
the duty is saturated at every sample, the counts never change (the axis did not move), the
regressors are too collinear to fit (MAX_CONDITION), the gain is not positive (the encoder counts
against the motor's direction), or tau sits at the search's edge (no first-order lag in the log).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nnik.dynamics.servo.batch_ls import batch_ls
from nnik.dynamics.servo.log_csv import ServoLog
from nnik.dynamics.servo.output_error import fit_output_error, tau_bounds
from nnik.dynamics.servo.rls import rls
from nnik.dynamics.servo.speed_model import DiscreteModel, SpeedModel
from nnik.dynamics.servo.servo_error import ServoError

Z95 = 1.959963984540054
MAX_CONDITION = 1e7  # of the column-scaled regressor matrix
RLS_AGREEMENT = 1e-3  # relative: RLS's tau and K against batch LS's
AXES = ("x", "y")


@dataclass(frozen=True)
class AxisFit:
    axis: str
    model: SpeedModel  # nnik's K, tau and their 95 % CIs (the output-error fit)
    coulomb_v: float  # Coulomb friction as volts lost against the motion (about 0 if none)
    speed_fit: float  # 1 - |increment residual| / |increments' spread| of the output-error fit
    discrete: DiscreteModel  # the seed's fit: the position transfer function by RLS
    theta_rls: np.ndarray  # a, b1, b0
    theta_ls: np.ndarray  # the same by batch least squares
    k_rls: float  # the seed's fit as K (counts/s/V) and tau (s)
    tau_rls_s: float
    samples: int


def regressors(dp: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """phi (rows k = 2..N-1 of the increment model) and y = dp[k]; dp[i] = p[i] - p[i-1] at index i."""
    return np.column_stack([dp[1:-1], u[1:-1], u[:-2]]), dp[2:]


def to_speed_model(theta: np.ndarray, tick_s: float) -> tuple[float, float]:
    """(K, tau) of theta = (a, b1, b0); NaN where theta is no first-order lag."""
    a, b1, b0 = theta[:3]
    if not 0 < a < 1:
        return math.nan, math.nan
    return (b1 + b0) / (tick_s * (1 - a)), -tick_s / math.log(a)


def _check_input(log: ServoLog, i: int) -> None:
    name = AXES[i]
    u = log.volts[:, i]
    if np.ptp(u) == 0:
        raise ServoError(f"no excitation on {name}: u_{name} is {u[0]:g} V at every sample")
    if log.duty is not None and (np.abs(log.duty[:, i]) >= 1.0).all():
        raise ServoError(f"u_{name} is saturated (|duty| = 1) at every sample: nothing but the supply's sign "
                        "excites the axis; lower the excitation's amplitude")
    if np.ptp(log.counts[:, i]) == 0:
        raise ServoError(f"count_{name} never changes: axis {name} did not move (no power, or the excitation is "
                        "below what breaks friction away)")


def _close(x: float, y: float) -> bool:
    return (math.isnan(x) and math.isnan(y)) or abs(x - y) <= RLS_AGREEMENT * max(abs(x), abs(y))


def seed_fit(dp: np.ndarray, u: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The seed's fit: (RLS's theta, batch LS's theta), refused when they disagree or the
    regressors are collinear."""
    phi, y = regressors(dp, u)
    ls = batch_ls(phi, y)
    if not ls.condition < MAX_CONDITION:
        raise ServoError(f"no excitation on {name}: the log does not excite the axis enough to fit its model "
                        f"(regressors' condition number {ls.condition:.3g}); excite it with `nnik excite`'s square "
                        "wave plus noise")
    theta = rls(phi, y).theta
    if not all(_close(float(p), float(q)) for p, q in zip(theta, ls.theta)):
        raise ServoError(f"axis {name}: recursive and batch least squares disagree (a {theta[0]:.6g} against "
                        f"{ls.theta[0]:.6g}): the log is numerically too poor to fit")
    return theta, ls.theta


def fit_axis(log: ServoLog, i: int) -> AxisFit:
    name, tick = AXES[i], log.tick_s
    _check_input(log, i)
    u = log.volts[:, i]
    dp = np.diff(log.counts[:, i], prepend=log.counts[0, i])
    theta, theta_ls = seed_fit(dp, u, name)
    oe = fit_output_error(dp, u, tick)
    if not oe.k > 0:
        raise ServoError(f"axis {name}: the fitted gain K = {oe.k:.4g} counts/s/V is not positive: the encoder counts "
                        "against the motor's direction (swap the encoder's A and B, or the motor's leads)")
    lo, hi = tau_bounds(tick)
    if not oe.tau > lo * 1.01:
        raise ServoError(f"axis {name}: the speed's lag is under half a tick (tau fits {oe.tau:.3g} s at the search's "
                         f"floor, {lo:g} s): the log's tick is too coarse to see it; log at a shorter tick")
    if not oe.tau < hi * 0.99:
        raise ServoError(f"axis {name}: tau fits {oe.tau:.4g} s at the search's ceiling ({hi:g} s): the log shows no "
                         "first-order lag (is it an open-loop excitation of this axis?)")
    dt, dk = (Z95 * math.sqrt(max(float(oe.cov[j, j]), 0.0)) for j in (0, 1))
    model = SpeedModel(oe.k, oe.tau, (oe.k - dk, oe.k + dk), (oe.tau - dt, oe.tau + dt))
    k_rls, tau_rls = to_speed_model(theta, tick)
    disc = DiscreteModel(tick, float(theta[0]), float(theta[1]), float(theta[2]))
    return AxisFit(name, model, oe.coulomb_v, oe.speed_fit, disc, theta, theta_ls, k_rls, tau_rls, len(dp) - 2)


def fit_log(log: ServoLog) -> tuple[AxisFit, AxisFit]:
    return fit_axis(log, 0), fit_axis(log, 1)
