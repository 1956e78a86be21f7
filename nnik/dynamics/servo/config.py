"""The DC-servo XY table's plant parameters (issue 28): `MotorAxis` per axis and `ServoConfig` for
both axes and the loop. The scenario's [servo] tables build them (nnik.machine.servo, which checks
them and re-exports these classes); the plant (nnik.dynamics.servo.plant) runs them.

Each axis is an armature-controlled DC motor (Ra, La, Ke = Kt in SI) driving a lead screw through
a gearbox of `gear_ratio` motor turns per screw turn; every torque, inertia and friction is at the
motor shaft, the backlash in table travel. The encoder sits on the motor shaft and counts
`counts_per_rev` (quadrature 4x) per screw turn, so `counts_per_rev / gear_ratio` per motor turn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from nnik.dynamics.servo.speed_model import SpeedModel


@dataclass(frozen=True)
class MotorAxis:
    """One axis' motor, gearbox and table (the [servo.x] / [servo.y] keys, SI units)."""

    ra_ohm: float
    la_h: float
    ke_v_s_rad: float
    j_kg_m2: float
    viscous_n_m_s_rad: float = 0.0
    coulomb_n_m: float = 0.0
    stiction_n_m: float = 0.0  # 0: off (the break-away is then the Coulomb torque)
    backlash_um: float = 0.0  # 0: off
    gear_ratio: float = 1.0

    @property
    def tau_e_s(self) -> float:
        """Electrical time constant La / Ra."""
        return self.la_h / self.ra_ohm

    @property
    def tau_m_s(self) -> float:
        """Mechanical (speed) time constant J Ra / (Ke^2 + Ra B), with La neglected."""
        return self.j_kg_m2 * self.ra_ohm / (self.ke_v_s_rad ** 2 + self.ra_ohm * self.viscous_n_m_s_rad)

    @property
    def break_away_n_m(self) -> float:
        """The motor torque the axis must exceed to start from rest."""
        return max(self.stiction_n_m, self.coulomb_n_m)

    def free_speed_rad_s(self, volts: float) -> float:
        """Steady motor speed at constant volts (>= 0): Ke i = B w + Tc, i = (V - Ke w) / Ra."""
        ke, ra = self.ke_v_s_rad, self.ra_ohm
        return max(0.0, (ke * abs(volts) - ra * self.coulomb_n_m) / (ke * ke + ra * self.viscous_n_m_s_rad))

    def no_load_current_a(self, volts: float) -> float:
        """Steady current at free speed: what friction costs."""
        w = self.free_speed_rad_s(volts)
        return (self.viscous_n_m_s_rad * w + self.coulomb_n_m) / self.ke_v_s_rad if w > 0 else abs(volts) / self.ra_ohm

    def stall_current_a(self, volts: float) -> float:
        return abs(volts) / self.ra_ohm


@dataclass(frozen=True)
class ServoConfig:
    """The two axes' plant and the chip's loop settings (the [servo] table)."""

    axes: tuple[MotorAxis, MotorAxis]
    tick_s: float = 0.005
    supply_v: float = 12.0
    duty_max: int = 255
    encoder: str = "quadrature"  # "quadrature" | "counter8"
    substeps: int = 40
    counts_per_rev: int = 1200  # per screw (gearbox output) turn
    lead_mm: float = 3.0
    identified: tuple[SpeedModel | None, SpeedModel | None] = field(default=(None, None))

    @property
    def um_per_count(self) -> float:
        return self.lead_mm * 1000.0 / self.counts_per_rev

    def counts_per_motor_rev(self, axis: int) -> float:
        return self.counts_per_rev / self.axes[axis].gear_ratio

    def volts(self, duty: int) -> float:
        return duty / self.duty_max * self.supply_v

    def free_speed_counts_s(self, axis: int, volts: float | None = None) -> float:
        w = self.axes[axis].free_speed_rad_s(self.supply_v if volts is None else volts)
        return w / (2 * math.pi) * self.counts_per_motor_rev(axis)
