"""CoreXY as firmware writes it: belt lengths a = x + y, b = x - y; x = (a + b)/2, y = (a - b)/2.

Motor angles are q1 = a / R1, q2 = b / R2, counted from the machine origin (x = y = 0).
"""

from __future__ import annotations

import numpy as np

from nnik.machine.kinematics.belt import BeltMechanism


class CoreXY(BeltMechanism):
    kind = "corexy"
    PARAMS = dict(BeltMechanism.BELT_PARAMS)

    def to_uv(self, belt):
        a, b = belt[:, 0], belt[:, 1]
        return np.stack([(a + b) / 2, (a - b) / 2], 1)

    def from_uv(self, uv):
        u, v = uv[:, 0], uv[:, 1]
        return np.stack([u + v, u - v], 1)
