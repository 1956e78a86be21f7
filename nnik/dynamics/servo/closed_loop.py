"""The closed loop in Python: a controller (duck-typed: reset(), tick(ref, pos) -> (duty_x, duty_y))
against the plant, one tick at a time.

At tick k the controller sees ref[k] and the encoder counts at tick k, and returns the duty the
plant holds from tick k to k + 1. The trace's row k is tick k: the counts and the table position
the controller saw there, and the duty it chose (rounded and saturated as the plant applies it).
The plant starts at rest at ref[0] unless start_counts says otherwise; `plant` replaces the
scenario's Plant by another with the same step() / counts / table_um / duty() (a drifting one,
nnik.dynamics.servo.drift), and `after_tick(k)` is called after the controller's tick k (to read
its state, e.g. a learning controller's weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.dynamics.servo.plant import Plant
from nnik.dynamics.servo.config import ServoConfig


@dataclass(frozen=True)
class Trace:
    ref: np.ndarray  # (N, 2) int64 counts
    counts: np.ndarray  # (N, 2) int64: what the controller read at tick k
    duty: np.ndarray  # (N, 2) int64: what the plant held from tick k
    table_um: np.ndarray  # (N, 2) float: the carriage's true position at tick k (after backlash)
    substep_counts: np.ndarray | None = None  # (N, S, 2): the counts at each substep's end of tick k
    duty_max: int = 255

    @property
    def saturated_fraction(self) -> float:
        """Share of ticks at which either duty sits at +-duty_max."""
        return float((np.abs(self.duty) >= self.duty_max).any(axis=1).mean()) if len(self.duty) else 0.0


def simulate(cfg: ServoConfig, controller, ref_counts, substeps: bool = False,
             start_counts: tuple[int, int] | None = None, plant=None, after_tick=None) -> Trace:
    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    n = len(ref)
    start = tuple(int(c) for c in (ref[0] if start_counts is None and n else (start_counts or (0, 0))))
    plant = Plant(cfg, start) if plant is None else plant
    controller.reset()
    counts = np.empty((n, 2), dtype=np.int64)
    duty = np.empty((n, 2), dtype=np.int64)
    table = np.empty((n, 2))
    subs = np.empty((n, cfg.substeps, 2), dtype=np.int64) if substeps else None
    for k in range(n):
        pos = plant.counts
        counts[k], table[k] = pos, plant.table_um
        d = controller.tick((int(ref[k, 0]), int(ref[k, 1])), pos)
        if after_tick is not None:
            after_tick(k)
        duty[k] = plant.duty(d[0]), plant.duty(d[1])
        rows = plant.step((duty[k, 0], duty[k, 1]))
        if subs is not None:
            subs[k] = rows
    return Trace(ref, counts, duty, table, subs, cfg.duty_max)
