"""The closed loop that tuning simulates: the integer controller against the IDENTIFIED model (per
axis a SpeedModel, nnik.dynamics.servo.speed_model), exactly discretised at the tick (zero-order
hold: the duty is held over the tick), with the duty's quantisation (the controller's integer duty)
and saturation (+-duty_max) and the encoder's quantisation (the controller reads floor(position)).

With coulomb_v (the identified Coulomb friction as volts lost against the motion, per axis; H2's
fit gives it) the model also sticks and slides, decided at each tick: a moving axis loses
coulomb_v against its speed (and stops, rather than reverses, if that alone would turn it); an axis
at rest stays there while |volts| <= coulomb_v, else it starts with |volts| - coulomb_v.

Positions are in counts, continuous; the table starts at rest in the middle of the reference's first
count (ref[0] + 0.5), so a carriage exactly on the reference reads the reference's count.
"""

from __future__ import annotations

import math

import numpy as np


def _friction(u: float, v: float, c: float) -> float:
    """The volts that drive the model after Coulomb friction c (volts) at speed v."""
    if v > 0.0:
        return u - c
    if v < 0.0:
        return u + c
    return 0.0 if abs(u) <= c else u - math.copysign(c, u)


def simulate_model(cfg, models, controller, ref_counts, coulomb_v=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(positions (N, 2) float counts at each tick, duties (N, 2) int) of the controller closing the
    loop around the speed models on ref_counts (N, 2)."""
    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    n = len(ref)
    coef = []
    for m in models:
        d = m.discrete(cfg.tick_s)
        a = d.a
        coef.append((a, m.tau_s * (1.0 - a), d.b1, m.k_counts_s_v * (1.0 - a), m.k_counts_s_v, m.tau_s))
    volts_per_duty = cfg.supply_v / cfg.duty_max
    dmax = cfg.duty_max
    p = [float(ref[0, 0]) + 0.5, float(ref[0, 1]) + 0.5]
    v = [0.0, 0.0]
    pos = np.empty((n, 2))
    duty = np.empty((n, 2), dtype=np.int64)
    controller.reset()
    refs = ref.tolist()
    for k in range(n):
        pos[k] = p
        d = controller.tick(refs[k], (math.floor(p[0]), math.floor(p[1])))
        for i in (0, 1):
            di = max(-dmax, min(dmax, int(d[i])))
            duty[k, i] = di
            a, cp, gp, gv, kk, tau = coef[i]
            u = di * volts_per_duty
            if coulomb_v[i]:
                u0, u = u, _friction(u, v[i], coulomb_v[i])
                v_next = a * v[i] + gv * u
                if v[i] != 0.0 and v_next * v[i] < 0.0 and abs(u0) <= coulomb_v[i]:  # friction stops it
                    v_inf = kk * u  # the speed it decays towards, opposite to v: it stops at t_stop
                    t_stop = tau * math.log(1.0 - v[i] / v_inf)
                    p[i], v[i] = p[i] + tau * v[i] + v_inf * t_stop, 0.0  # the exact travel until then
                    continue
            p[i], v[i] = p[i] + cp * v[i] + gp * u, a * v[i] + gv * u
    return pos, duty
