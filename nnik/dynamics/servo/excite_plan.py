"""`nnik excite`'s design on a scenario's plant: probe each axis with a step, choose the square's
amplitude and period from what the step shows, play the excitation on the plant and keep its log.

Choices (each axis on its own; the same scenario and seed give the same duties):
- The probe: PROBE_FRACTION of the supply held for PROBE_S from rest; K is the last PROBE_TAIL's
  mean speed per volt, tau the time the speed takes to reach 63.2 % of it (friction, backlash and
  the electrical lag included, as the plant has them).
- Amplitude A = AMPLITUDE_FRACTION of the supply (6 V of 12: well above the ~1 V a DC gearmotor
  needs to start, with room for the noise's 3 sigma under the supply), lowered when the square's
  swing, K * A * half_period / 2 each side of the start, would leave more than SWING_FRACTION of the
  stroke's half; refused if that takes it below MIN_AMPLITUDE_V.
- Half period: HALF_PERIOD_TAUS[axis] x tau (5 on X, 7 on Y: the axes' squares never run in step),
  at least MIN_HALF_TICKS ticks.
- Noise: sigma^2 = 0.3 * A (the seed, read literally; nnik.dynamics.servo.excitation).
- The table starts at the middle of each stroke; the log is refused if it leaves the strokes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nnik.dynamics.servo.excitation import AxisExcitation, duties
from nnik.dynamics.servo.servo_error import ServoError

PROBE_S = 2.0
PROBE_FRACTION = 0.5
PROBE_TAIL = 0.25
AMPLITUDE_FRACTION = 0.5
SWING_FRACTION = 0.5
MIN_AMPLITUDE_V = 2.0
HALF_PERIOD_TAUS = (5.0, 7.0)
MIN_HALF_TICKS = 4
AXES = ("x", "y")


@dataclass(frozen=True)
class Probe:
    k_counts_s_v: float
    tau_s: float


@dataclass(frozen=True)
class Excitation:
    axes: tuple[AxisExcitation, AxisExcitation]
    probes: tuple[Probe, Probe]
    duty: np.ndarray  # (N, 2) int
    counts: np.ndarray  # (N, 2) int: the plant's encoder counts at the start of each tick
    table_um: np.ndarray  # (N, 2) the carriage's true position at the start of each tick
    start_counts: tuple[int, int]


def _plant(cfg, start):
    from nnik.dynamics.servo.plant import Plant

    return Plant(cfg, start_counts=start)


def probe(cfg) -> tuple[Probe, Probe]:
    """Each axis's step response on the scenario's plant (both axes at once, from rest)."""
    n = max(int(round(PROBE_S / cfg.tick_s)), 20)
    duty = int(round(PROBE_FRACTION * cfg.duty_max))
    volts = duty / cfg.duty_max * cfg.supply_v
    plant = _plant(cfg, (0, 0))
    counts = np.empty((n + 1, 2))
    counts[0] = plant.counts
    for k in range(n):
        counts[k + 1] = plant.step((duty, duty))[-1]
    speed = np.diff(counts, axis=0) / cfg.tick_s  # the mean speed over each tick
    out = []
    for i, name in enumerate(AXES):
        v_ss = float(speed[-max(int(PROBE_TAIL * n), 1):, i].mean())
        if not v_ss > 0:
            raise ServoError(f"axis {name} does not move at {volts:.3g} V (half the supply) in the scenario's plant: its "
                            "friction holds it, and the excitation's square is no larger")
        k_hit = int(np.argmax(speed[:, i] >= (1 - math.exp(-1)) * v_ss))
        out.append(Probe(v_ss / volts, max((k_hit + 0.5) * cfg.tick_s, cfg.tick_s)))
    return out[0], out[1]


def plan(cfg, stroke_counts: tuple[float, float], probes: tuple[Probe, Probe]) -> tuple[AxisExcitation, ...]:
    axes = []
    for i, (p, name) in enumerate(zip(probes, AXES)):
        half = max(int(math.ceil(HALF_PERIOD_TAUS[i] * p.tau_s / cfg.tick_s)), MIN_HALF_TICKS)
        amp = AMPLITUDE_FRACTION * cfg.supply_v
        swing = p.k_counts_s_v * amp * half * cfg.tick_s / 2
        room = SWING_FRACTION * stroke_counts[i] / 2
        if swing > room:
            amp *= room / swing
        if amp < MIN_AMPLITUDE_V:
            raise ServoError(f"axis {name}: a square of {MIN_AMPLITUDE_V:g} V for {half} ticks would swing "
                            f"{p.k_counts_s_v * MIN_AMPLITUDE_V * half * cfg.tick_s / 2:.0f} counts each side, more "
                            f"than the stroke allows ({room:.0f})")
        axes.append(AxisExcitation(round(amp, 3), half))
    return tuple(axes)


def excite(cfg, workspace_um: tuple[tuple[float, float], tuple[float, float]], seconds: float, seed: int) -> Excitation:
    """workspace_um: ((x_lo, x_hi), (y_lo, y_hi)) of the carriage in um."""
    upc = cfg.um_per_count
    stroke = tuple((hi - lo) / upc for lo, hi in workspace_um)
    start = tuple(int(round((lo + hi) / 2 / upc)) for lo, hi in workspace_um)
    probes = probe(cfg)
    axes = plan(cfg, stroke, probes)
    n = int(round(seconds / cfg.tick_s))
    duty = duties(axes, n, cfg.supply_v, cfg.duty_max, seed)
    plant = _plant(cfg, start)
    counts = np.empty((n, 2), dtype=np.int64)
    table = np.empty((n, 2))
    for k in range(n):
        counts[k], table[k] = plant.counts, plant.table_um
        plant.step((int(duty[k, 0]), int(duty[k, 1])))
    for i, name in enumerate(AXES):
        lo, hi = workspace_um[i]
        if table[:, i].min() < lo or table[:, i].max() > hi:
            raise ServoError(f"the excitation drives {name} out of its stroke ({table[:, i].min() / 1000:.1f} to "
                            f"{table[:, i].max() / 1000:.1f} mm of {lo / 1000:g}..{hi / 1000:g}); give fewer --seconds")
    return Excitation(axes, probes, duty, counts, table, start)
