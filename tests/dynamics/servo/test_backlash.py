"""The play operator: its shortcut for monotonic runs equals the sequential clip."""

from __future__ import annotations

import numpy as np
from hypothesis import given, strategies as st

from nnik.dynamics.servo.backlash import play


def sequential(t, motor, b):
    out = []
    for m in motor:
        t = min(max(t, m - b / 2), m + b / 2)
        out.append(t)
    return np.array(out)


@given(steps=st.lists(st.floats(-50, 50), min_size=1, max_size=60), b=st.floats(0.0, 40.0),
       offset=st.floats(-1.0, 1.0), monotonic=st.booleans())
def test_play_is_the_sequential_clip(steps, b, offset, monotonic):
    steps = np.abs(steps) if monotonic else np.array(steps)
    motor = 100.0 + np.cumsum(steps)
    t0 = 100.0 + offset * b / 2  # anywhere in the gap around the previous motor sample
    got = play(t0, 100.0, motor, b)
    np.testing.assert_allclose(got, sequential(t0, motor, b) if b > 0 else motor, rtol=0, atol=1e-9)
    assert np.all(np.abs(got - motor) <= b / 2 + 1e-9)
