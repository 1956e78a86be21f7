"""A Cartesian XY table on lead screws (seed 001's rig): each axis is one motor turning one screw.

Joint q (rad) is the screw's angle, counted from the origin where the table homes (x = y = 0):
q = 2 pi x / lead, x = lead q / (2 pi). The same lead on both axes (the rig's 3 mm/rev); a dc_servo
actuator counts the screw's angle in encoder counts, a stepper in microsteps.
"""

from __future__ import annotations

import math

import numpy as np

from nnik.machine.kinematics.base import Mechanism, as_points
from nnik.machine.params import Param, length_mm


class XYTable(Mechanism):
    kind = "xy_table"
    family = "screw"
    PARAMS = {
        "lead_mm": Param("float", required=True, check=length_mm,
                         doc="xy_table: table travel per screw revolution (3 on seed 001's rig)"),
    }

    @property
    def mm_per_rad(self) -> float:
        return self.params["lead_mm"] / (2 * math.pi)

    def forward(self, q):
        return as_points(q) * self.mm_per_rad

    def inverse(self, p):
        return as_points(p) / self.mm_per_rad
