"""Shared machinery of the belt machines (HBOT, CoreXY): pulleys, axis skew and nonlinear errors.

A belt machine maps motor angles q to ideal carriage coordinates (u, v) through its belt layout
(each subclass gives `to_uv` and `from_uv`). The frame then places (u, v) on the plane:

    position = u (cos B, sin B) + v (cos A, sin A)        (seed 004; B is the X axis, A the Y axis)

which is affine: nominal A = 90 deg, B = 0 deg is the ideal machine. Real machines add nonlinear
errors, modelled here with the workspace centre c and half-size h, s = (p - c) / h:

- pulley eccentricity: each belt pays out R q + e sin(q + phase) instead of R q;
- belt stretch: the X scale grows linearly along Y, x <- c_x + (x - c_x)(1 + stretch s_y);
- gantry racking: the gantry yaws by racking_deg s_y, rotating the head's offset along X;
- rail bow: the X rail sags quadratically, y <- y + bow_mm (1 - s_x^2).

With no nonlinear term the inverse is exact (the 2x2 map inverted); otherwise Newton on the
forward map solves it to 1e-10 mm and fails loudly if it does not converge.
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.machine.kinematics.base import Mechanism, as_points
from nnik.machine.params import Param, length_mm, validate_table, within

DISTORTION = {
    "A_deg": Param("float", default=90.0, check=within(0.0, 180.0, open_lo=True, unit=" deg"), doc="direction of the Y axis (nominal 90)"),
    "B_deg": Param("float", default=0.0, check=within(-90.0, 90.0, unit=" deg"), doc="direction of the X axis (nominal 0)"),
    "bow_mm": Param("float", default=0.0, check=within(-1000.0, 1000.0, unit=" mm"), doc="quadratic sag of the X rail at mid-span"),
    "stretch": Param("float", default=0.0, check=within(-0.5, 0.5), doc="relative X-scale change from mid-Y to the Y edge"),
    "racking_deg": Param("float", default=0.0, check=within(-45.0, 45.0, unit=" deg"), doc="gantry yaw at the Y edge (linear in Y)"),
    "eccentricity_mm": Param("float", default=0.0, check=within(-100.0, 100.0, unit=" mm"), doc="pulley eccentricity (belt pay-out error)"),
    "eccentricity_phase_deg": Param("float", default=0.0, check=within(-360.0, 360.0, unit=" deg"), doc="phase of the eccentricity"),
}
NONLINEAR_KEYS = ("bow_mm", "stretch", "racking_deg", "eccentricity_mm")

MAX_SKEW_DEG = 45.0  # axes further from perpendicular make a near-singular, not a skewed, machine
NEWTON_TOL_MM = 1e-10
NEWTON_MAX_ITER = 40


class BeltMechanism(Mechanism):
    family = "belt"
    BELT_PARAMS = {
        "R1_mm": Param("float", check=length_mm, doc="pulley radius, motor 1 (default mm_per_rev/2pi)"),
        "R2_mm": Param("float", check=length_mm, doc="pulley radius, motor 2 (default mm_per_rev/2pi)"),
        "distortion": Param("table", default=None, doc="axis skew and nonlinear errors"),
    }

    def __init__(self, params, workspace, source="<scenario>"):
        super().__init__(params, workspace, source)
        self.dist = validate_table(params.get("distortion") or {}, DISTORTION, source, "mechanism.distortion")
        a, b = np.radians(self.dist["A_deg"]), np.radians(self.dist["B_deg"])
        self.frame = np.array([[np.cos(b), np.cos(a)], [np.sin(b), np.sin(a)]])
        between = abs(float(np.degrees(np.arcsin(np.clip(np.linalg.det(self.frame), -1.0, 1.0)))))
        if between < 90.0 - MAX_SKEW_DEG:
            raise NnikError(
                f"non-invertible or near-singular frame: A_deg={self.dist['A_deg']:g} and B_deg={self.dist['B_deg']:g} "
                f"put the X and Y axes {between:.2f} deg from parallel; they must be within {MAX_SKEW_DEG:g} deg "
                "of perpendicular",
                source,
                "[mechanism.distortion]",
            )
        self.frame_inv = np.linalg.inv(self.frame)
        self.nonlinear = any(self.dist[k] != 0.0 for k in NONLINEAR_KEYS)

    @property
    def radii(self) -> np.ndarray:
        return np.array([self.params["R1_mm"], self.params["R2_mm"]])

    # Belt layout: motor angles <-> ideal carriage coordinates (u, v), both in mm after the radii.
    def to_uv(self, belt: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def from_uv(self, uv: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _payout(self, q):
        """Belt length paid out by each pulley (mm), eccentricity included."""
        belt = q * self.radii
        e = self.dist["eccentricity_mm"]
        if e:
            belt = belt + e * np.sin(q + np.radians(self.dist["eccentricity_phase_deg"]))
        return belt

    def _warp(self, p):
        """The position-dependent (nonlinear) errors applied to the affine position."""
        c, h = self.workspace.center, self.workspace.half
        s = (p - c) / h
        dx = (p[:, 0] - c[0]) * (1 + self.dist["stretch"] * s[:, 1])
        theta = np.radians(self.dist["racking_deg"]) * s[:, 1]
        x = c[0] + dx * np.cos(theta)
        y = p[:, 1] + dx * np.sin(theta) + self.dist["bow_mm"] * (1 - s[:, 0] ** 2)
        return np.stack([x, y], 1)

    def forward(self, q):
        q = as_points(q)
        p = self.to_uv(self._payout(q)) @ self.frame.T
        return self._warp(p) if self.nonlinear else p

    def affine_inverse(self, p):
        """Exact inverse of the machine without its nonlinear errors."""
        return self.from_uv(as_points(p) @ self.frame_inv.T) / self.radii

    def inverse(self, p):
        p = as_points(p)
        q = self.affine_inverse(p)
        if not self.nonlinear:
            return q
        h = 1e-6
        for _ in range(NEWTON_MAX_ITER):
            r = self.forward(q) - p
            if np.abs(r).max() <= NEWTON_TOL_MM:
                return q
            cols = []
            for j in range(2):
                dq = np.zeros(2)
                dq[j] = h
                cols.append((self.forward(q + dq) - self.forward(q - dq)) / (2 * h))
            jac = np.stack(cols, 2)  # (N, 2 outputs, 2 joints)
            try:
                q = q - np.linalg.solve(jac, r[:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                raise NnikError("Newton inverse met a singular Jacobian; the machine's scale or distortion "
                                "cannot be inverted", self.source, "[mechanism]") from None
        worst = np.abs(self.forward(q) - p).max(1).argmax()
        raise NnikError(
            f"Newton inverse did not converge to {NEWTON_TOL_MM:g} mm near x={p[worst, 0]:.3f}, "
            f"y={p[worst, 1]:.3f} mm; the distortion is too strong to invert there",
            self.source,
            "[mechanism.distortion]",
        )

    def check_reach(self):
        # The map must stay one-to-one: the Jacobian determinant keeps its sign over the workspace.
        pts = self.workspace.grid(41)
        q = self.inverse(pts)
        h = 1e-6
        cols = [(self.forward(q + h * e) - self.forward(q - h * e)) / (2 * h) for e in np.eye(2)]
        det = np.linalg.det(np.stack(cols, 2))
        if not (np.all(det > 0) or np.all(det < 0)):
            raise NnikError("the distortion folds the workspace (singular Jacobian)", self.source, "[mechanism.distortion]")
