"""The plant Jacobian each neural controller learns with, by the seed's impulse method on
normalised signals (seed 001, section 3.1: input volts / 12 V, output position / 40 mm).

The seed took the Jacobian as "the linear relation between the output sequence y(k) and the
impulsive input sequence u(k)", on normalised signals, and measured X 1.0103 and Y 0.6047 on its
rig. Its equations are lost; ours, exactly:

    u_n[k] = volts[k] / 12 V            one impulse: u_n[0] = 1 (12 V held over tick 0), then 0
    y_n[k] = position[k] / 40 mm        the identified model's response (SpeedModel.simulate)
    J      = (y_n[K] - y_n[0]) / (u_n[0] * T)

with T the tick (s) and K the first tick at or after 30 tau (the response has settled to
exp(-30) of itself). J is in 1/s: the normalised position the impulse leaves behind per
normalised volt-second. The plant integrates (position is the speed's integral), so an impulse
leaves a displacement, not a decaying response; dividing by the impulse's area makes J a
property of the axis, not of the tick: for the first-order speed model it is exactly
K * 12 V * um_per_count / 40 mm (K in counts/s/V), whatever tau and T, and the simulation agrees
to within exp(-30). Per tick instead of per second it would be 200x smaller at 5 ms; the seed's
1.0103 then would be 40 mm * 1.01 per 12 V over 5 ms = 8 m/s, which no 12 V lead-screw table
does, while per second it is 40 mm/s at 12 V: a plausible rig. So per second is our reading.

The 12 V and 40 mm are the seed's normalisation, fixed (not the scenario's supply or stroke), so
our figures stand beside the seed's: its rig's X was faster than its Y (ratio 0.60); ours come from
the identified models (xy_table: about 0.65 /s for both, Y/X = K_y / K_x).
"""

from __future__ import annotations

import math

import numpy as np

NORM_VOLTS = 12.0  # the seed's input reference
NORM_MM = 40.0  # the seed's output reference
SETTLE_TAUS = 30.0
SEED_JACOBIANS = (1.0103, 0.6047)  # X, Y as the seed measured them (a different rig)


def impulse_jacobian(model, cfg) -> float:
    """J (1/s) of one axis' identified SpeedModel at cfg's tick (cfg.tick_s, cfg.um_per_count): the
    normalised displacement a one-tick 12 V impulse leaves, per normalised volt-second."""
    tick = cfg.tick_s
    n = int(math.ceil(SETTLE_TAUS * model.tau_s / tick)) + 2
    volts = np.zeros(n)
    volts[0] = NORM_VOLTS
    counts = model.simulate(volts, tick)
    y_n = (counts[-1] - counts[0]) * cfg.um_per_count / (NORM_MM * 1000.0)
    return float(y_n / (1.0 * tick))
