"""The axis model against scipy's lsim and against the analytic lag a / wn^2."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import TransferFunction, lsim

from nnik.dynamics.axis import discrete, static_lag, tip, wn


@settings(max_examples=25, deadline=None)
@given(f=st.floats(5, 150), zeta=st.floats(0, 1.5), dt=st.sampled_from([1e-4, 1e-3]), seed=st.integers(0, 2**16))
def test_tip_equals_lsim_with_a_held_input(f, zeta, dt, seed):
    rng = np.random.default_rng(seed)
    n = 600
    base = np.cumsum(rng.integers(-1, 2, n)).astype(float)  # a step stream
    w = wn(f)
    sys = TransferFunction([2 * zeta * w, w * w], [1, 2 * zeta * w, w * w])
    t = np.arange(n) * dt
    _, want, _ = lsim(sys, base, t, X0=None, interp=False)
    # lsim starts from a zero state: compare from rest at 0
    got = tip(np.concatenate([[0.0], base]), dt, f, zeta)[1:]
    _, want0, _ = lsim(sys, np.concatenate([[0.0], base]), np.arange(n + 1) * dt, interp=False)
    assert np.max(np.abs(got - want0[1:])) < 1e-6 * (1 + np.max(np.abs(base)))
    assert want.shape == got.shape


def test_step_response_is_the_analytic_one():
    f, zeta, dt = 40.0, 0.1, 1e-4
    t = np.arange(4000) * dt
    y = tip(np.ones_like(t), dt, f, zeta)  # at rest at 1: stays there
    assert np.max(np.abs(y - 1)) < 1e-12
    base = np.concatenate([[0.0], np.ones(3999)])
    y = tip(base, dt, f, zeta)
    w, wd = wn(f), wn(f) * math.sqrt(1 - zeta**2)
    tt = t[1:] - dt  # the step starts at dt
    # base-excited: x = 1 - e^{-zeta w t} (cos wd t - (zeta w / wd) sin wd t) ... with the damper's
    # impulse: 1 - e^{-zeta w t} (cos wd t + (zeta w / wd) sin wd t) + (2 zeta w / wd) e^{-zeta w t} sin wd t
    e = np.exp(-zeta * w * tt)
    want = 1 - e * (np.cos(wd * tt) - (zeta * w / wd) * np.sin(wd * tt))
    assert np.max(np.abs(y[1:] - want)) < 1e-9
    # the first overshoot of a zeta = 0.1 belt
    assert 1.7 < y.max() < 1.9


def test_lag_under_constant_acceleration_is_a_over_wn_squared():
    f, zeta, a, dt = 35.0, 0.1, 3000.0, 1e-5
    t = np.arange(0, 0.6, dt)
    held = 0.5 * a * t**2
    lag = held - tip(held, dt, f, zeta)
    # the held input itself trails the parabola by v dt / 2; the rest is a / wn^2 = 62 um
    v_end = a * t[-1]
    assert math.isclose(lag[-1] - v_end * dt / 2, static_lag(a, f), rel_tol=0.01)
    assert math.isclose(static_lag(3000.0, 35.0), 0.062, rel_tol=0.01)


def test_discretisation_is_the_matrix_exponential_not_euler():
    ad, bd, c = discrete(40.0, 0.1, 1e-3)
    w = wn(40.0)
    euler = np.array([[1, 1e-3], [-w * w * 1e-3, 1 - 2 * 0.1 * w * 1e-3]])
    assert np.max(np.abs(ad - euler)) > 1e-3  # Euler would be visibly different at 1 ms
    assert np.allclose(ad @ np.array([1.0, 0.0]) + bd[:, 0] * w * w * 0, ad[:, 0])
    # a fixed point: base = tip = 1 at rest -> x = (1 / w^2, 0) stays
    x = np.array([1 / w**2, 0.0])
    assert np.allclose(ad @ x + bd[:, 0] * 1.0, x)
