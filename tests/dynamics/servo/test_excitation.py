"""The seed's excitation: sigma^2 = 0.3 x A (read literally), a square centred on the start, the
duty quantised and clamped, the same seed the same duties."""

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from nnik.dynamics.servo.excitation import AxisExcitation, duties, square


@settings(max_examples=25, deadline=None)
@given(n=st.integers(10, 3000), half=st.integers(2, 200))
def test_square_starts_with_a_half_segment_so_its_integral_stays_centred(n, half):
    s = square(n, half)
    assert set(np.unique(s)) <= {-1.0, 1.0} and s[0] == 1.0
    first = int(np.argmax(s < 0)) if (s < 0).any() else n
    assert first == min(half - half // 2, n)
    walk = np.cumsum(s)
    assert walk.max() <= half - half // 2 and walk.min() >= -(half // 2 + 1)


@settings(max_examples=15, deadline=None)
@given(amp=st.floats(1.0, 10.0), seed=st.integers(0, 2**32 - 1))
def test_noise_variance_is_030_times_the_amplitude_in_volts(amp, seed):
    ax = AxisExcitation(amp, 40)
    assert ax.sigma_v ** 2 == 0.3 * amp or math.isclose(ax.sigma_v ** 2, 0.3 * amp)
    n, supply, dmax = 40000, 1000.0, 2**15 - 1  # a fine duty so the quantisation does not hide the variance
    d = duties((ax, AxisExcitation(amp, 57)), n, supply, dmax, seed)
    volts = d / dmax * supply
    noise = volts[:, 0] - amp * square(n, 40)
    assert abs(noise.var() / (0.3 * amp) - 1) < 0.05
    assert abs(noise.mean()) < 5 * math.sqrt(0.3 * amp / n)


def test_duty_is_quantised_clamped_reproducible_and_the_axes_differ():
    axes = (AxisExcitation(11.0, 30), AxisExcitation(11.0, 42))
    a = duties(axes, 4000, 12.0, 255, 5)
    assert a.dtype == np.int64 and np.abs(a).max() == 255  # 11 V + noise reaches the 12 V supply: clamped
    assert (duties(axes, 4000, 12.0, 255, 5) == a).all()
    assert not (duties(axes, 4000, 12.0, 255, 6) == a).all()
    assert not (a[:, 0] == a[:, 1]).all()
