"""Each kinematics agrees with the published formulas and conventions."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.errors import NnikError
from nnik.machine.kinematics import KINDS, Workspace

WS = Workspace((-100.0, 100.0), (-100.0, 100.0))


def test_gimbal_matches_eq9_where_x_positive():
    m = KINDS["galvo_gimbal"]({"z_mm": 300.0, "max_mech_deg": 45.0}, WS)
    rng = np.random.default_rng(1)
    p = np.stack([rng.uniform(0.1, 100, 5000), rng.uniform(-100, 100, 5000)], 1)
    x, y, z = p[:, 0], p[:, 1], 300.0
    alpha = 0.5 * np.arctan(y / z)
    beta_eq9 = 0.5 * np.arctan(y / (x * np.sin(2 * alpha)))
    q = m.inverse(p)
    np.testing.assert_allclose(q[:, 0], alpha, atol=1e-13)
    ok = np.abs(y) > 1e-3  # eq. 9 is 0/0 at y = 0
    np.testing.assert_allclose(q[ok, 1], beta_eq9[ok], atol=1e-10)


def test_gimbal_continuous_at_x0_and_defined_at_y0():
    m = KINDS["galvo_gimbal"]({"z_mm": 300.0, "max_mech_deg": 45.0}, WS)
    q = m.inverse(np.array([[-1e-9, 0.0], [0.0, 0.0], [1e-9, 0.0], [50.0, 0.0]]))
    assert np.all(np.isfinite(q))
    assert abs(q[0, 1] - q[2, 1]) < 1e-11
    np.testing.assert_allclose(q[1], [0.0, np.pi / 4], atol=1e-15)


def test_dual_with_e0_is_the_gimbal_optics():
    """With e = 0 the two-mirror head deflects like one mirror: y = d tan(py), x = d/cos(py) tan(px)."""
    m = KINDS["galvo_dual"]({"d_mm": 200.0, "e_mm": 0.0, "max_mech_deg": 45.0}, WS)
    q = m.inverse(np.array([[30.0, -40.0]]))
    py, px = 2 * q[0, 1], 2 * q[0, 0]
    assert abs(200 * np.tan(py) + 40) < 1e-12
    assert abs(200 / np.cos(py) * np.tan(px) - 30) < 1e-12


def test_dual_ignoring_e_costs_about_e_tan20():
    d, e = 200.0, 10.0
    with_e = KINDS["galvo_dual"]({"d_mm": d, "e_mm": e, "max_mech_deg": 45.0}, WS)
    without = KINDS["galvo_dual"]({"d_mm": d, "e_mm": 0.0, "max_mech_deg": 45.0}, WS)
    q = np.array([[np.radians(10.0), 0.0]])  # 20 deg optical on X
    miss = with_e.forward(q)[0, 0] - without.forward(q)[0, 0]
    assert miss == pytest.approx(e * np.tan(np.radians(20)), rel=1e-12)


def test_ideal_corexy_is_a_plus_b_minus():
    r = 40 / (2 * np.pi)
    m = KINDS["corexy"]({"R1_mm": r, "R2_mm": r, "distortion": None}, WS)
    p = np.random.default_rng(2).uniform(-100, 100, (1000, 2))
    belts = m.inverse(p) * r
    np.testing.assert_allclose(belts[:, 0], p[:, 0] + p[:, 1], atol=1e-12)
    np.testing.assert_allclose(belts[:, 1], p[:, 0] - p[:, 1], atol=1e-12)


def test_ideal_hbot_is_seed004_and_corexy_up_to_sign_and_offset():
    X, C, r = 400.0, 60.0, 6.0
    m = KINDS["hbot"]({"X_mm": X, "C_mm": C, "R1_mm": r, "R2_mm": r, "distortion": None}, WS)
    p = np.random.default_rng(3).uniform(-100, 100, (1000, 2))
    x, y = p[:, 0], p[:, 1]
    q = m.inverse(p)
    np.testing.assert_allclose(q[:, 0], (y + X - C / 2 - x) / r, atol=1e-12)
    np.testing.assert_allclose(q[:, 1], (-y - x + C / 2) / r, atol=1e-12)
    # documented convention: R q1 = -(x - y) + X - C/2 and R q2 = -(x + y) + C/2
    np.testing.assert_allclose(r * q[:, 1], -(x + y) + C / 2, atol=1e-12)
    np.testing.assert_allclose(r * q[:, 0], -(x - y) + X - C / 2, atol=1e-12)


def test_skew_is_the_seed004_frame_map():
    dist = {"A_deg": 92.0, "B_deg": 1.0}
    m = KINDS["corexy"]({"R1_mm": 5.0, "R2_mm": 5.0, "distortion": dist}, WS)
    ideal = KINDS["corexy"]({"R1_mm": 5.0, "R2_mm": 5.0, "distortion": None}, WS)
    q = np.array([[3.0, -2.0]])
    u, v = ideal.forward(q)[0]
    a, b = np.radians(92.0), np.radians(1.0)
    np.testing.assert_allclose(m.forward(q)[0], u * np.array([np.cos(b), np.sin(b)]) + v * np.array([np.cos(a), np.sin(a)]))
    assert not m.nonlinear


def test_a_equals_b_is_refused():
    with pytest.raises(NnikError, match="non-invertible"):
        KINDS["corexy"]({"R1_mm": 5.0, "R2_mm": 5.0, "distortion": {"A_deg": 30.0, "B_deg": 30.0}}, WS)


def test_newton_failure_is_reported():
    # a bow of 1 m on a 200 mm rail with 45 deg of racking folds the map: Newton cannot converge
    # and must say so (the largest values the range checks allow)
    m = KINDS["corexy"]({"R1_mm": 5.0, "R2_mm": 5.0, "distortion": {"bow_mm": 1000.0, "racking_deg": 45.0}}, WS)
    with pytest.raises(NnikError, match="Newton inverse did not converge"):
        m.inverse(np.random.default_rng(0).uniform(-100, 100, (200, 2)))


def test_distortions_beyond_any_frame_are_refused():
    with pytest.raises(NnikError, match=r"bow_mm: must be in \[-1000, 1000\] mm"):
        KINDS["corexy"]({"R1_mm": 5.0, "R2_mm": 5.0, "distortion": {"bow_mm": 1e6}}, WS)
