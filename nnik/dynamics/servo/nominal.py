"""The speed model a scenario's plant has by construction, to hold an identified one against: the
linear DC motor's (friction, stiction and backlash left out) DC gain in encoder counts/s per volt,
Ke / (Ke^2 + Ra B) rad/s/V at the motor times counts per motor turn / 2 pi, and its slow (speed)
pole as tau; La's fast pole is what a first-order model leaves out. `equivalent_tau_s` is the
first-order lag with the same low-frequency phase, the sum of both time constants: what a
first-order fit of a log of the plant approaches."""

from __future__ import annotations

import math

import numpy as np

from nnik.dynamics.servo.speed_model import SpeedModel


def nominal_model(cfg, axis: int) -> SpeedModel:
    ax = cfg.axes[axis]
    ra, la, ke, j, b = ax.ra_ohm, ax.la_h, ax.ke_v_s_rad, ax.j_kg_m2, ax.viscous_n_m_s_rad
    gain = ke / (ke * ke + ra * b)
    poles = np.linalg.eigvals(np.array([[-ra / la, -ke / la], [ke / j, -b / j]]))
    slow = float(np.max(poles.real))
    return SpeedModel(gain * cfg.counts_per_motor_rev(axis) / (2 * math.pi), -1.0 / slow)


def equivalent_tau_s(cfg, axis: int) -> float:
    """The sum of the linear motor's two time constants (speed and electrical)."""
    ax = cfg.axes[axis]
    ra, la, ke, j, b = ax.ra_ohm, ax.la_h, ax.ke_v_s_rad, ax.j_kg_m2, ax.viscous_n_m_s_rad
    a = np.array([[-ra / la, -ke / la], [ke / j, -b / j]])
    return float(-np.trace(a) / np.linalg.det(a))  # -(l1 + l2) / (l1 l2) = 1/-l1 + 1/-l2
