"""The closed loop that tuning simulates: the integer controller against the IDENTIFIED model (per
axis a SpeedModel, nnik.dynamics.servo.speed_model), exactly discretised at the tick (zero-order
hold: the duty is held over the tick), with the duty's quantisation (the controller's integer duty)
and saturation (+-duty_max) and the encoder's quantisation (the controller reads floor(position)).

Positions are in counts, continuous; the table starts at rest in the middle of the reference's first
count (ref[0] + 0.5), so a carriage exactly on the reference reads the reference's count.
"""

from __future__ import annotations

import math

import numpy as np


def simulate_model(cfg, models, controller, ref_counts) -> tuple[np.ndarray, np.ndarray]:
    """(positions (N, 2) float counts at each tick, duties (N, 2) int) of the controller closing the
    loop around the speed models on ref_counts (N, 2)."""
    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    n = len(ref)
    coef = []
    for m in models:
        d = m.discrete(cfg.tick_s)
        a = d.a
        coef.append((a, m.tau_s * (1.0 - a), d.b1, m.k_counts_s_v * (1.0 - a)))
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
            a, cp, gp, gv = coef[i]
            u = di * volts_per_duty
            p[i], v[i] = p[i] + cp * v[i] + gp * u, a * v[i] + gv * u
    return pos, duty
