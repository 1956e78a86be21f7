"""The standard two-mirror galvo head (XY2-100 class).

Mirror X sits e before mirror Y; mirror Y is at working distance d from the plane. The optical
angle is twice the mechanical one. Forward: y = d tan(py), x = (d / cos(py) + e) tan(px), with
p* the optical angles. Inverse: py = atan(y / d), px = atan(x / (sqrt(d^2 + y^2) + e)).
Joints are the mechanical angles (px/2, py/2); rest is (0, 0). With e = 0 this is the gimbal.
"""

from __future__ import annotations

import numpy as np

from nnik.machine.kinematics.base import Mechanism, as_points
from nnik.machine.kinematics.galvo_gimbal import MAX_MECH, check_incidence
from nnik.machine.params import MAX_LENGTH_MM, Param, length_mm, within


class GalvoDual(Mechanism):
    kind = "galvo_dual"
    family = "galvo"
    joint_names = ("theta_x", "theta_y")
    PARAMS = {
        "e_mm": Param("float", required=True, check=within(0.0, MAX_LENGTH_MM, unit=" mm"), doc="mirror X to mirror Y"),
        "d_mm": Param("float", required=True, check=length_mm, doc="mirror Y to target plane"),
        "max_mech_deg": MAX_MECH,
    }

    def inverse(self, p):
        p = as_points(p)
        x, y = p[:, 0], p[:, 1]
        d, e = self.params["d_mm"], self.params["e_mm"]
        py = np.arctan2(y, d)
        px = np.arctan2(x, np.hypot(d, y) + e)
        return np.stack([px / 2, py / 2], 1)

    def forward(self, q):
        q = as_points(q)
        px, py = 2 * q[:, 0], 2 * q[:, 1]
        d, e = self.params["d_mm"], self.params["e_mm"]
        return np.stack([(d / np.cos(py) + e) * np.tan(px), d * np.tan(py)], 1)

    def check_reach(self):
        check_incidence(self, self.params["d_mm"], "d_mm")
        self.check_swing(self.params["max_mech_deg"])
