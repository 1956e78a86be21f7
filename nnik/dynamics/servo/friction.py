"""One tick of one axis with Coulomb, viscous and stiction friction, without chatter.

Viscous friction is in the linear model (nnik.dynamics.servo.motor). Coulomb friction Tc and the
break-away torque Ts (stiction, >= Tc; Tc when stiction is off) are applied between substeps as a
stick/slip switch (Karnopp's method):

- stuck: the speed is exactly 0 and the angle fixed; only the current moves (a scalar ZOH). The
  axis breaks away at the end of the first substep where the motor torque |Ke i| exceeds Ts, in
  the direction of that torque;
- sliding in direction d: the friction d Tc is held over the substeps (an input of the exact
  discretisation) until the speed would reach or cross zero; that substep ends at speed exactly 0,
  and the axis sticks there if |Ke i| <= Ts, else it slides on in the direction of Ke i.

A tick is a few such segments, each done at once with the precomputed powers (no loop over
substeps while the axis keeps its state). The friction never flips sign between substeps while the
axis rests, so there is no chatter: held below break-away the axis stays exactly still. The one
approximation is the stop: it is taken at the end of the substep in which the speed reaches zero,
at the angle where the speed, linear between the substep's ends, crosses zero (so the angle never
steps back against the motion); an error within one substep's travel at each stop.
With neither Coulomb nor stiction the axis is linear and the tick is one exact product.
"""

from __future__ import annotations

import numpy as np

from nnik.dynamics.servo.motor import AxisMatrices
from nnik.dynamics.servo.config import MotorAxis


def tick(m: AxisMatrices, ax: MotorAxis, x0: np.ndarray, stuck: bool, volts: float) -> tuple[np.ndarray, bool]:
    """The state (i, w, theta) at the end of each substep, (S, 3), and whether the axis rests stuck
    at the end, from the state x0 (stuck or not) with `volts` held over the tick."""
    s = len(m.powers)
    out = np.empty((s, 3))
    ke, tc, tb = ax.ke_v_s_rad, ax.coulomb_n_m, ax.break_away_n_m
    if tb == 0.0:  # viscous friction only: linear, exact
        out[:] = m.powers @ x0 + m.inputs @ np.array([volts, 0.0])
        return out, False
    x, k = x0, 0
    while k < s:
        r = s - k
        if stuck:
            decay = m.stuck_decay[:r]
            i = decay * x[0] + (1.0 - decay) * (volts / ax.ra_ohm)
            over = np.flatnonzero(np.abs(ke * i) > tb)
            n = r if over.size == 0 else int(over[0]) + 1
            out[k:k + n, 0], out[k:k + n, 1], out[k:k + n, 2] = i[:n], 0.0, x[2]
            stuck = over.size == 0
        else:
            d = np.sign(x[1]) if x[1] != 0.0 else np.sign(ke * x[0])
            traj = m.powers[:r] @ x + m.inputs[:r] @ np.array([volts, d * tc])
            stop = np.flatnonzero(traj[:, 1] * d <= 0.0)
            if stop.size == 0:
                out[k:] = traj
                return out, False
            n = int(stop[0]) + 1
            out[k:k + n] = traj[:n]
            # the stop: speed 0, the angle where the speed (linear between the substep's ends)
            # reaches 0, so the angle never steps back against the motion
            _, w_prev, th_prev = traj[n - 2] if n > 1 else x
            span = w_prev - traj[n - 1, 1]
            frac = w_prev / span if span != 0.0 else 0.0
            out[k + n - 1, 1:] = 0.0, th_prev + 0.5 * w_prev * frac * m.h
            stuck = abs(ke * out[k + n - 1, 0]) <= tb
        k += n
        x = out[k - 1]
    return out, stuck
