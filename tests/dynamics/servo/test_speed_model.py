"""SpeedModel: its discretisation is scipy's exact ZOH one, and simulate() follows it."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.signal import cont2discrete, dlsim

from nnik.dynamics.servo.speed_model import SpeedModel
from nnik.dynamics.servo.servo_error import ServoError


@settings(max_examples=30, deadline=None)
@given(k=st.floats(100, 1e5), tau=st.floats(0.002, 0.5), tick=st.sampled_from([0.001, 0.005, 0.01]))
def test_discrete_is_scipys_zoh(k, tau, tick):
    d = SpeedModel(k, tau).discrete(tick)
    num, den, _ = cont2discrete(([k], [tau, 1.0, 0.0]), tick, "zoh")
    np.testing.assert_allclose(d.den, den, rtol=1e-9)
    np.testing.assert_allclose(d.num, np.ravel(num)[1:], rtol=1e-7, atol=1e-9 * k * tick)


@settings(max_examples=20, deadline=None)
@given(k=st.floats(100, 1e5), tau=st.floats(0.005, 0.3), seed=st.integers(0, 2**31))
def test_simulate_is_the_transfer_function(k, tau, seed):
    u = np.random.default_rng(seed).uniform(-12, 12, 200)
    m = SpeedModel(k, tau)
    d = m.discrete(0.005)
    _, y = dlsim((d.num, d.den, 0.005), u)
    np.testing.assert_allclose(m.simulate(u, 0.005), np.ravel(y), rtol=1e-7, atol=1e-6 * k)


def test_steady_speed_is_k_volts():
    p = SpeedModel(4000.0, 0.03).simulate(np.full(400, 6.0), 0.005)
    assert (p[-1] - p[-2]) / 0.005 == pytest.approx(24000.0, rel=1e-9)


@pytest.mark.parametrize("k,tau", [(0, 0.1), (-5, 0.1), (100, 0), (100, float("nan"))])
def test_nonsense_is_refused(k, tau):
    with pytest.raises(ServoError):
        SpeedModel(k, tau)
