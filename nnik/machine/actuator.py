"""Actuators: joint angles (rad) to the units the firmware commands (microsteps or DAC LSB)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.errors import NnikError
from nnik.machine.params import Param, within

STEPPER = {
    "kind": Param("str", required=True),
    "steps_per_rev": Param("int", default=200, check=within(1, 100_000), doc="full steps per revolution"),
    "microsteps": Param("int", default=16, check=within(1, 1024), doc="microsteps per full step"),
    "mm_per_rev": Param("float", check=within(0.0, 10_000.0, open_lo=True, unit=" mm"), doc="belt travel per motor revolution (belt machines)"),
}
DAC = {
    "kind": Param("str", required=True),
    "bits": Param("int", default=16, check=lambda v: None if 2 <= v <= 24 else f"must be 2..24, got {v}"),
    "optical_range_deg": Param("float", default=40.0, check=within(0.0, 180.0, open_lo=True, unit=" deg"), doc="full-scale optical swing"),
}
DC_SERVO = {
    "kind": Param("str", required=True),
    "counts_per_rev": Param("int", default=1200, check=within(4, 1_000_000),
                            doc="encoder counts (quadrature 4x) per revolution of the gearbox's output, the screw"),
}
SCHEMAS = {"stepper": STEPPER, "dac": DAC, "dc_servo": DC_SERVO}
MAX_UNITS = 2.0**30  # commands the int32 outputs of the generated C carry with headroom


@dataclass(frozen=True)
class Actuator:
    kind: str
    unit: str  # "microstep" | "lsb" | "count"
    units_per_rad: float  # per radian of joint (mechanical) angle
    params: dict
    code_range: tuple[int, int] | None = None  # DAC codes that exist

    @classmethod
    def from_params(cls, p: dict) -> "Actuator":
        if p["kind"] == "stepper":
            per_rev = p["steps_per_rev"] * p["microsteps"]
            return cls("stepper", "microstep", per_rev / (2 * np.pi), p)
        if p["kind"] == "dc_servo":  # the screw's angle in encoder counts
            return cls("dc_servo", "count", p["counts_per_rev"] / (2 * np.pi), p)
        full = 2 ** p["bits"]
        # optical = 2 x mechanical, so one mechanical radian is two optical ones
        per_rad = full / np.radians(p["optical_range_deg"]) * 2
        return cls("dac", "lsb", per_rad, p, (-(full // 2), full // 2 - 1))

    def to_units(self, dq: np.ndarray) -> np.ndarray:
        """Joint angle from rest (rad) -> actuator units (float)."""
        return dq * self.units_per_rad

    def from_units(self, u: np.ndarray) -> np.ndarray:
        return u / self.units_per_rad

    def check_range(self, units: np.ndarray, source: str, key: str = "[workspace]",
                    needs: str = "workspace needs") -> None:
        """Raise NnikError if commands (actuator units) leave the DAC's codes or int32 headroom."""
        worst = float(np.abs(units).max())
        if self.code_range is None:
            if worst > MAX_UNITS:
                raise NnikError(f"{needs} {worst:.3g} {self.unit}s, beyond the int32 range of the generated C "
                                f"(|q| <= 2^30); check mm_per_rev, the pulley radii and the microsteps", source, key)
            return
        lo, hi = self.code_range
        if units.min() < lo - 0.5 or units.max() > hi + 0.5:
            raise NnikError(
                f"{needs} DAC code {worst:.0f}, beyond the {self.params['bits']}-bit range "
                f"[{lo}, {hi}] over {self.params['optical_range_deg']:g} deg optical",
                source,
                key,
            )

    def describe(self) -> str:
        if self.kind == "stepper":
            p = self.params
            return f"stepper {p['steps_per_rev']} steps/rev x {p['microsteps']} microsteps"
        if self.kind == "dc_servo":
            return f"DC servo, {self.params['counts_per_rev']} encoder counts/rev"
        return f"DAC {self.params['bits']} bit over {self.params['optical_range_deg']:g} deg optical"
