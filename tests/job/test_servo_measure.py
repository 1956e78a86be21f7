"""A closed-loop job's figures (nnik.job.servo_measure): the contour error is the exact distance to
the reference path (not to the tick's point), and a step's overshoot, settling and steady state."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from nnik.job.servo_measure import path_distance, steps


def brute(points, path):
    a, b = path[:-1], path[1:]
    out = []
    for p in points:
        ab = b - a
        L2 = (ab * ab).sum(axis=1)
        t = np.clip(((p - a) * ab).sum(axis=1) / np.where(L2 > 0, L2, 1), 0, 1)
        out.append(np.hypot(*(p - (a + ab * t[:, None])).T).min())
    return np.array(out)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(2, 60), jump=st.floats(1, 50000), noise=st.floats(0, 3000))
def test_the_contour_error_is_the_exact_distance_to_the_path(seed, n, jump, noise):
    rng = np.random.default_rng(seed)
    path = np.cumsum(rng.normal(size=(n, 2)) * 40, axis=0)
    path[n // 2:] += jump  # a step: one long segment
    path = np.repeat(path, rng.integers(1, 4, n), axis=0)  # holds: repeated points
    pts = path[rng.integers(0, len(path), 50)] + rng.normal(size=(50, 2)) * noise
    np.testing.assert_allclose(path_distance(pts, path), brute(pts, path), atol=1e-6)


def test_a_carriage_lagging_along_the_path_has_no_contour_error():
    path = np.column_stack([np.arange(0, 10000, 5.0), np.zeros(2000)])
    lagging = path - [300.0, 0.0]  # 300 um behind in time, on the path
    lagging[:60] = path[0]
    assert path_distance(lagging, path).max() == 0.0


def test_a_step_s_overshoot_settling_and_steady_state():
    ref = np.zeros((400, 2))
    ref[100:] = [10000.0, 0.0]
    t = np.arange(300) * 0.005
    x = 10000 * (1 - np.exp(-t / 0.05) * np.cos(t * 40))  # an underdamped answer
    pos = np.zeros((400, 2))
    pos[100:, 0] = x
    pos[100:, 1] = 3.0
    (s,) = steps(ref, pos, (100,), 0.005, 2.5)
    assert s["overshoot_um"] == pytest.approx((x - 10000).max())
    outside = np.flatnonzero(np.hypot(x - 10000, 3.0) > 200)
    assert s["settling_s"] == pytest.approx((outside[-1] + 1) * 0.005)
    assert s["steady_state_um"] == pytest.approx(3.0, abs=0.01)
