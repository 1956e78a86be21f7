"""The XY table's plant in Python (issue 28): per axis an armature-controlled DC motor through a
gearbox and a lead screw, integrated in `substeps` exact steps per tick (nnik.dynamics.servo.motor)
with friction switched between them (friction), gearbox backlash between the motor and the table
(backlash) and the encoder on the motor shaft (encoder).

The duty is the chip's: an integer, saturated at +-duty_max, held over the tick (a float duty is
rounded to the nearest integer). The armature sees its average, duty / duty_max * supply_v (the
PWM's period is taken as short against La/Ra). The motor starts at rest, stuck, in the middle of
its start count (angle (count + 1/2) / counts per motor turn), the table in the middle of the play.

    plant = Plant(cfg, start_counts=(0, 0))
    rows = plant.step((duty_x, duty_y))   # (substeps, 2) int64: the count at each substep's end
    plant.counts, plant.raw8, plant.table_um
"""

from __future__ import annotations

import math

import numpy as np

from nnik.dynamics.servo import backlash, encoder, friction
from nnik.dynamics.servo.motor import AxisMatrices
from nnik.dynamics.servo.config import ServoConfig


class Plant:
    def __init__(self, cfg: ServoConfig, start_counts: tuple[int, int] = (0, 0)):
        self.cfg = cfg
        h = cfg.tick_s / cfg.substeps
        self._m = [AxisMatrices.build(ax, h, cfg.substeps) for ax in cfg.axes]
        self._cpr = [cfg.counts_per_motor_rev(a) for a in range(2)]
        # table travel (um) per motor radian
        self._um_per_rad = [cfg.lead_mm * 1000.0 / (2 * math.pi * ax.gear_ratio) for ax in cfg.axes]
        self._x = [np.array([0.0, 0.0, (int(c) + 0.5) * 2 * math.pi / cpr]) for c, cpr in zip(start_counts, self._cpr)]
        self._stuck = [True, True]
        self._counts = [int(c) for c in start_counts]
        self._table = [float(x[2] * k) for x, k in zip(self._x, self._um_per_rad)]
        self.last_states: list[np.ndarray] = []  # the last tick's (substeps, 3) states per axis
        self.last_table_um: np.ndarray | None = None  # the last tick's (substeps, 2) table positions

    def duty(self, d) -> int:
        """The integer duty the chip can output: rounded, saturated at +-duty_max."""
        dm = self.cfg.duty_max
        return int(min(max(round(float(d)), -dm), dm))

    def step(self, duty: tuple[int, int]) -> np.ndarray:
        """Integrate one tick with `duty` held; the encoder count at each substep's end (S, 2)."""
        cfg = self.cfg
        rows = np.empty((cfg.substeps, 2), dtype=np.int64)
        table = np.empty((cfg.substeps, 2))
        self.last_states = []
        for a, ax in enumerate(cfg.axes):
            volts = cfg.volts(self.duty(duty[a]))
            states, self._stuck[a] = friction.tick(self._m[a], ax, self._x[a], self._stuck[a], volts)
            motor_um = states[:, 2] * self._um_per_rad[a]
            table[:, a] = backlash.play(self._table[a], self._x[a][2] * self._um_per_rad[a], motor_um,
                                        ax.backlash_um)
            c = encoder.counts(states[:, 2], self._cpr[a])
            if cfg.encoder == "counter8":
                c = encoder.unwrap8(self._counts[a], encoder.raw8(c))
            rows[:, a] = c
            self._x[a] = states[-1].copy()
            self._table[a] = float(table[-1, a])
            self._counts[a] = int(c[-1])
            self.last_states.append(states)
        self.last_table_um = table
        return rows

    @property
    def counts(self) -> tuple[int, int]:
        """The encoder counts now (unwrapped 8-bit readings in counter8 mode)."""
        return self._counts[0], self._counts[1]

    @property
    def raw8(self) -> tuple[int, int]:
        """The 8-bit counters' values now (counter8 mode's readings)."""
        return self._counts[0] & 0xFF, self._counts[1] & 0xFF

    @property
    def table_um(self) -> tuple[float, float]:
        """The carriage's true position (after the backlash), um."""
        return self._table[0], self._table[1]

    def state(self, axis: int) -> tuple[float, float, float]:
        """(armature current A, motor speed rad/s, motor angle rad) of one axis now."""
        i, w, th = self._x[axis]
        return float(i), float(w), float(th)
