"""Reference paths for the tuning tests, planned-looking: trapezoidal speed profiles (accelerate,
cruise, decelerate) sampled at the tick and rounded to counts: a corner (X then Y, with a stop at
the corner) and a circle started and ended at rest along a ramped angle. Also the speed models the
scenario's plant has by construction (the linear motor's gain and slow pole), standing for the
identified ones."""

from __future__ import annotations

import math

import numpy as np

from nnik.dynamics.servo.speed_model import SpeedModel
from nnik.machine.scenario import load_scenario
from tests.conftest import DATASETS


def xy_table_cfg():
    return load_scenario(DATASETS / "xy_table.toml").servo


def plant_models(cfg) -> tuple[SpeedModel, SpeedModel]:
    out = []
    for i, ax in enumerate(cfg.axes):
        ra, la, ke, j, b = ax.ra_ohm, ax.la_h, ax.ke_v_s_rad, ax.j_kg_m2, ax.viscous_n_m_s_rad
        poles = np.linalg.eigvals(np.array([[-ra / la, -ke / la], [ke / j, -b / j]]))
        k = ke / (ke * ke + ra * b) * cfg.counts_per_motor_rev(i) / (2 * math.pi)
        out.append(SpeedModel(k, -1.0 / float(np.max(poles.real))))
    return tuple(out)


def trapezoid(length: float, v: float, a: float, tick_s: float) -> np.ndarray:
    """Distance along a move at each tick (rest to rest)."""
    ta = min(v / a, math.sqrt(length / a))
    vp = a * ta
    tc = max(0.0, (length - a * ta * ta) / vp)
    t_end = 2 * ta + tc
    t = np.arange(0.0, t_end + tick_s, tick_s)
    s = np.where(t < ta, 0.5 * a * t * t,
                 np.where(t < ta + tc, 0.5 * a * ta * ta + vp * (t - ta),
                          length - 0.5 * a * np.clip(t_end - t, 0, None) ** 2))
    return np.clip(s, 0.0, length)


def hold(um: np.ndarray, ticks: int) -> np.ndarray:
    return np.vstack([um, np.repeat(um[-1:], ticks, axis=0)])


def corner(cfg, x_mm=20.0, y_mm=15.0, v_mm_s=15.0, a_mm_s2=200.0) -> np.ndarray:
    t = cfg.tick_s
    sx = trapezoid(x_mm * 1000, v_mm_s * 1000, a_mm_s2 * 1000, t)
    sy = trapezoid(y_mm * 1000, v_mm_s * 1000, a_mm_s2 * 1000, t)
    um = np.vstack([np.zeros((20, 2)), np.c_[sx, np.zeros_like(sx)], np.c_[np.full_like(sy, x_mm * 1000), sy]])
    return counts(cfg, hold(um + 10_000.0, 60))


def circle(cfg, r_mm=10.0, v_mm_s=10.0, a_mm_s2=200.0) -> np.ndarray:
    s = trapezoid(2 * math.pi * r_mm * 1000, v_mm_s * 1000, a_mm_s2 * 1000, cfg.tick_s)
    th = s / (r_mm * 1000)
    um = np.c_[r_mm * 1000 * np.cos(th), r_mm * 1000 * np.sin(th)] + 30_000.0
    return counts(cfg, hold(np.vstack([np.repeat(um[:1], 20, axis=0), um]), 60))


def counts(cfg, um: np.ndarray) -> np.ndarray:
    return np.floor(um / cfg.um_per_count).astype(np.int64)
