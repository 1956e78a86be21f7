"""The chip's timing figures from its pins: the samples it computed too late (missed_samples) and
the longest busy stretch inside the motion (cpu_report's worst_sample_cycles)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.job.measure import cpu_report, missed_samples

CPT = 1600  # cycles a tick at 10 kHz


def segments(ticks, speed, chord=None):
    n = len(ticks)
    return SimpleNamespace(ticks=np.asarray(ticks, np.int64), speed_q16=np.asarray(speed, np.int64),
                           chord=np.zeros(n, np.int64) if chord is None else np.asarray(chord, np.int64))


def on_time(ticks, start=1000):
    return start + np.concatenate([[0], np.cumsum(np.asarray(ticks, np.int64) * CPT)[:-1]])


@settings(max_examples=50, deadline=None)
@given(st.lists(st.integers(1, 40), min_size=2, max_size=60), st.data())
def test_a_gap_while_moving_is_a_miss_and_at_rest_is_not(ticks, data):
    n = len(ticks)
    speed = data.draw(st.lists(st.integers(0, 3).map(lambda v: v * 65536), min_size=n, max_size=n))
    marks = on_time(ticks)
    assert missed_samples(marks, segments(ticks, speed), CPT) == 0  # on time: no miss
    k = data.draw(st.integers(0, n - 2))
    late = marks.copy()
    late[k + 1:] += data.draw(st.integers(CPT, 50 * CPT))  # the queue ran dry before segment k + 1
    want = int(speed[k] > 0 and speed[k + 1] > 0)
    assert missed_samples(late, segments(ticks, speed), CPT) == want
    # a shaped move (the head still settling) counts as moving, as a planned speed does
    chord = [1] * n
    assert missed_samples(late, segments(ticks, [0] * n, chord), CPT) == 1


def test_jitter_below_half_a_tick_is_on_time():
    ticks = [10, 10, 10]
    marks = on_time(ticks) + np.array([0, CPT // 2, 3])
    assert missed_samples(marks, segments(ticks, [65536] * 3), CPT) == 0


def test_worst_sample_is_the_longest_busy_stretch_inside_the_motion():
    run = SimpleNamespace(marks=np.array([10_000, 20_000]), idle_cycle=100_000, end_cycle=120_000,
                          busy=np.array([[0, 9_000], [9_500, 12_000], [30_000, 34_000], [99_000, 110_000]]))
    busy = (run.busy[:, 1] - run.busy[:, 0]).astype(np.float64)
    out = cpu_report(run, busy, samples=10)
    assert out["worst_sample_cycles"] == 4_000  # the start's 9,000 and the tail past the idle cycle are outside
    assert out["cycles_per_sample"]["max"] == 11_000
    assert out["cpu_sample_loop"] == (2_000 + 4_000 + 1_000) / 90_000
