"""grbl's float planner on the chip's sample clock (nnik/bench/planner_sampled.py) against the
continuous one (nnik/bench/planner_oracle.py): equal where the queue never limits the motion,
never faster where it does, and slower as the queue shortens."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.bench import planner_oracle as oracle
from nnik.bench import planner_sampled
from nnik.bench.planner_paths import chord_ops, path_ops
from nnik.firmware.config import MachineConfig

CFG = MachineConfig(origin_um=(0, 0))


@settings(max_examples=40, deadline=None, database=None)
@given(length=st.integers(50, 200000), feed=st.integers(60, 6000), acc=st.integers(100, 10000),
       hz=st.sampled_from([500, 1000, 2000]))
def test_a_lone_line_is_the_continuous_trapezoid(length, feed, acc, hz):
    cfg = MachineConfig(origin_um=(0, 0), accel_um_s2=(acc * 1000, acc * 1000), sample_hz=hz)
    ops = [("push", length, 0, feed * 1000, 0, 0), ("flush",)]
    assert planner_sampled.plan_time(ops, cfg) == pytest.approx(oracle.plan(ops, cfg).time_s, rel=1e-9, abs=1e-9)


def test_chords_cost_the_sample_clock_and_the_short_queue():
    """A 5 mm circle in 10 um chords: unlimited lookahead is the continuous plan; a queue of 16
    and of 8 blocks on the sample clock are slower than the continuous planner with the same
    queue, 8 slower than 16; 200 um chords with 16 blocks cost nothing."""
    ops = chord_ops(10, 5000, 1.0, 3_000_000)
    t_inf = oracle.plan(ops, CFG, None).time_s
    assert planner_sampled.plan_time(ops, CFG, None) == pytest.approx(t_inf, rel=1e-9)
    t16, t8 = (planner_sampled.plan_time(ops, CFG, n) for n in (16, 8))
    assert t8 > t16 > oracle.plan(ops, CFG, 16).time_s > t_inf
    long_chords = chord_ops(200, 5000, 1.0, 3_000_000)
    assert planner_sampled.plan_time(long_chords, CFG, 16) == pytest.approx(oracle.plan(long_chords, CFG, 16).time_s, rel=1e-9)


def test_runs_between_stops_add_up():
    ops = path_ops([("line", 3000.0, 0.0), ("rev", 2000.0), ("line", 500.0, 90.0)], 3_000_000)
    runs = oracle.blocks_of(ops, CFG)
    assert len(runs) == 1 and planner_sampled.plan_time(ops + ops, CFG) > planner_sampled.plan_time(ops, CFG)
