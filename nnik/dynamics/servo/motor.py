"""The linear part of one axis, discretised exactly with scipy once per plant.

State x = (i, w, theta): armature current (A), motor speed (rad/s), motor angle (rad). Inputs
u = (V, Tf): armature volts and a friction torque held over the substep (N m, signed against the
motion):

    La di/dt = V - Ra i - Ke w
    J  dw/dt = Ke i - B w - Tf              (Kt = Ke in SI units)
       dth/dt = w

With u held over a substep h (zero-order hold) the exact discretisation is
x[k+1] = Ad x[k] + Bd u[k], from one matrix exponential (scipy.linalg.expm of the augmented
[[A, B], [0, 0]] h). A tick of S substeps with u held is then x_k = Ad^k x_0 + (sum_{j<k} Ad^j Bd) u,
k = 1..S; `powers` and `inputs` hold those S matrices so that any run of substeps is one numpy
product, with no scipy call while simulating.

At rest (stuck by friction) w = 0 and theta are fixed and only the current moves:
i[k] = a^k i[0] + (1 - a^k) V / Ra, a = exp(-h Ra / La) (`stuck_decay`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from nnik.dynamics.servo.config import MotorAxis


def continuous(ax: MotorAxis) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the linear model above."""
    ra, la, ke, j, b = ax.ra_ohm, ax.la_h, ax.ke_v_s_rad, ax.j_kg_m2, ax.viscous_n_m_s_rad
    a = np.array([[-ra / la, -ke / la, 0.0], [ke / j, -b / j, 0.0], [0.0, 1.0, 0.0]])
    bm = np.array([[1.0 / la, 0.0], [0.0, -1.0 / j], [0.0, 0.0]])
    return a, bm


def discretise(a: np.ndarray, bm: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH discretisation (Ad, Bd) over h seconds."""
    n, m = bm.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, bm
    e = expm(aug * h)
    return e[:n, :n], e[:n, n:]


@dataclass(frozen=True)
class AxisMatrices:
    """One axis' precomputed substep matrices for a tick of `substeps` substeps of h seconds."""

    powers: np.ndarray  # (S, 3, 3): Ad^k, k = 1..S
    inputs: np.ndarray  # (S, 3, 2): sum_{j<k} Ad^j Bd, k = 1..S
    stuck_decay: np.ndarray  # (S,): a^k, k = 1..S
    h: float  # the substep, s

    @classmethod
    def build(cls, ax: MotorAxis, h: float, substeps: int) -> "AxisMatrices":
        ad, bd = discretise(*continuous(ax), h)
        powers = np.empty((substeps, 3, 3))
        inputs = np.empty((substeps, 3, 2))
        p, g = np.eye(3), np.zeros((3, 2))
        for k in range(substeps):
            g = g + p @ bd
            p = ad @ p
            powers[k], inputs[k] = p, g
        decay = np.exp(-h * ax.ra_ohm / ax.la_h * np.arange(1, substeps + 1))
        return cls(powers, inputs, decay, h)
