"""Single mirror on a two-axis gimbal (seed 000, eq. 5-9).

The mirror centre is the origin and the target plane is parallel to x-y at distance z. The mirror
turns by alpha about X and beta about Y; the beam turns by twice that. The beam direction is
(cos 2b, sin 2a sin 2b, cos 2a sin 2b), so the rest pose (plane centre) is a = 0, b = 45 deg.
Inverse: a = atan2(y, z)/2, b = atan2(sqrt(y^2 + z^2), x)/2, which equals eq. 9 for x > 0, has no
0/0 at y = 0 and is continuous across x = 0.
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.machine.kinematics.base import Mechanism, as_points
from nnik.machine.params import Param, length_mm


def _mech_limit(v):
    return None if 0 < v <= 45 else f"must be in (0, 45] degrees, got {v}"


MAX_INCIDENCE_DEG = 75.0  # beyond this the beam grazes the plane: the IK's slope grows without bound


def check_incidence(mech, distance_mm: float, key: str) -> None:
    """Reject a galvo whose beam meets the plane near grazing incidence somewhere in the
    workspace: there the IK is near its singularity (distance -> 0), a few micrometres swing the
    mirror by degrees, and no small network or table follows it."""
    ws = mech.workspace
    far = max(np.hypot(x, y) for x in ws.x_mm for y in ws.y_mm)
    incidence = float(np.degrees(np.arctan2(far, distance_mm)))
    if incidence > MAX_INCIDENCE_DEG:
        raise NnikError(
            f"near-singular geometry: the beam meets the plane {incidence:.2f} deg from its normal at the "
            f"workspace's far corner (at most {MAX_INCIDENCE_DEG:g}); increase {key} or shrink [workspace]",
            mech.source,
            f"[mechanism] {key}",
        )


MAX_MECH = Param("float", default=45.0, check=_mech_limit, doc="largest mirror swing from rest, mechanical deg")


class GalvoGimbal(Mechanism):
    kind = "galvo_gimbal"
    family = "galvo"
    joint_names = ("alpha", "beta")
    PARAMS = {
        "z_mm": Param("float", required=True, check=length_mm, doc="mirror centre to target plane"),
        "max_mech_deg": MAX_MECH,
    }

    @property
    def q_rest(self) -> np.ndarray:
        return np.array([0.0, np.pi / 4])

    def inverse(self, p):
        p = as_points(p)
        x, y = p[:, 0], p[:, 1]
        z = self.params["z_mm"]
        alpha = 0.5 * np.arctan2(y, z)
        beta = 0.5 * np.arctan2(np.hypot(y, z), x)
        return np.stack([alpha, beta], 1)

    def forward(self, q):
        q = as_points(q)
        a2, b2 = 2 * q[:, 0], 2 * q[:, 1]
        z = self.params["z_mm"]
        d = z / (np.cos(a2) * np.sin(b2))  # beam length to the plane
        return np.stack([d * np.cos(b2), d * np.sin(a2) * np.sin(b2)], 1)

    def check_reach(self):
        check_incidence(self, self.params["z_mm"], "z_mm")
        self.check_swing(self.params["max_mech_deg"])
