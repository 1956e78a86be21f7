"""HBOT as in seed 004: frame span X, carriage width C, pulley radii R1, R2, motor angles q1, q2.

Ideal forward: x = (X - R2 q2 - R1 q1) / 2, y = (-X + C - R2 q2 + R1 q1) / 2.
Ideal inverse: q1 = (y + X - C/2 - x) / R1, q2 = (-y - x + C/2) / R2.
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.machine.kinematics.belt import BeltMechanism
from nnik.machine.params import Param, length_mm


class HBot(BeltMechanism):
    kind = "hbot"
    PARAMS = {
        "X_mm": Param("float", required=True, check=length_mm, doc="frame span"),
        "C_mm": Param("float", required=True, check=length_mm, doc="carriage width"),
        **BeltMechanism.BELT_PARAMS,
    }

    def __init__(self, params, workspace, source="<scenario>"):
        if not params["C_mm"] < params["X_mm"]:
            raise NnikError(f"the carriage ({params['C_mm']:g} mm) must be narrower than the frame span X_mm "
                            f"({params['X_mm']:g} mm) it runs in", source, "[mechanism] C_mm")
        super().__init__(params, workspace, source)

    def to_uv(self, belt):
        X, C = self.params["X_mm"], self.params["C_mm"]
        b1, b2 = belt[:, 0], belt[:, 1]
        return np.stack([(X - b2 - b1) / 2, (-X + C - b2 + b1) / 2], 1)

    def from_uv(self, uv):
        X, C = self.params["X_mm"], self.params["C_mm"]
        u, v = uv[:, 0], uv[:, 1]
        return np.stack([v + X - C / 2 - u, -v - u + C / 2], 1)
