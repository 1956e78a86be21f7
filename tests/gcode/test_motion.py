"""The firmware's motion logic in Python: segment ends, arcs, modes, errors (no IK needed)."""

from __future__ import annotations

from math import ceil, isqrt

import numpy as np
import pytest

from nnik.firmware_config import MachineConfig
from nnik.gcode.motion import Interpreter, interpret, plan_steps

CFG = MachineConfig(origin_um=(0, 0), seg_um=500)


def ends(lines, cfg=CFG):
    plan = interpret(lines, cfg)
    assert all(r == "ok" for r in plan.replies), plan.replies
    return plan, np.asarray(plan.ends)


def test_line_is_cut_into_equal_segments_ending_exactly():
    plan, e = ends(["G1 X10 Y3.3 F600"])
    L = isqrt(10000**2 + 3300**2)
    assert len(e) == ceil(L / 500)
    assert tuple(e[-1]) == (10000, 3300)
    steps = np.diff(np.vstack([[0, 0], e]), axis=0)
    assert np.all(np.hypot(*steps.T) <= 501)
    assert plan.feed == [600000] * len(e)


def test_full_circle_by_g2_is_four_quarters_of_short_chords():
    plan, e = ends(["G0 X8", "G2 X8 Y0 I-8 J0 F1500"])
    arc = e[plan.moves[1].first_seg:]
    c = np.array([0, 0])
    r = np.hypot(*(arc - c).T)
    assert np.all(np.abs(r - 8000) <= 1)
    chords = np.hypot(*np.diff(np.vstack([[8000, 0], arc]), axis=0).T)
    assert chords.max() <= 500 and chords.min() > 250
    prev = np.vstack([[8000, 0], arc])[:-1]
    cross = prev[:, 0] * arc[:, 1] - prev[:, 1] * arc[:, 0]
    assert np.all(cross < 0)  # clockwise all the way round
    assert tuple(arc[-1]) == (8000, 0)
    ang = np.unwrap(np.arctan2(arc[:, 1], arc[:, 0]))
    assert ang[0] - ang[-1] == pytest.approx(2 * np.pi, abs=0.1)


def test_inch_and_incremental_modes_stay_modal():
    plan, e = ends(["G20 G91 G1 X1 F10", "Y-0.5", "G21 G90 G1 X0 Y0"])
    assert [tuple(m.end) for m in plan.moves] == [(25400, 0), (25400, -12700), (0, 0)]
    assert plan.feed[0] == 254000  # 10 in/min


@pytest.mark.parametrize("line, msg", [
    ("G1 X1 I2", "I/J need G2 or G3"),
    ("G2 X1 Y1", "arc needs I, J or R"),
    ("G2 X10 I1", "arc end is off the circle"),
    ("G2 I0 J0", "arc radius is zero"),
    ("G1 X1 F0.5", "feed below 1 mm/min"),
])
def test_bad_lines_move_nothing(line, msg):
    it = Interpreter(CFG)
    it.line("G1 X1 Y1")
    n = len(it.plan.ends)
    reply = it.line(line)
    assert reply == f"error: line 2: {msg}"
    assert len(it.plan.ends) == n and it.pos == (1000, 1000)


def test_coordinates_beyond_the_limit_are_refused():
    it = Interpreter(CFG)
    for _ in range(10):
        reply = it.line("G20 G91 G0 X9999")
    assert reply == "error: line 10: coordinate out of range"


def test_ticks_follow_the_feed_and_never_outrun_the_steps():
    plan, _ = ends(["G1 X10 F600"])
    seg = plan_steps(plan, CFG, lambda p: (p // 40, np.zeros(len(p), np.int64)))  # 40 um per step
    assert np.all(seg.ticks == 500 * 60 * 10000 // 600000)  # 0.5 mm at 10 mm/s = 500 ticks
    fast, _ = ends(["G0 X10"])
    seg = plan_steps(fast, CFG, lambda p: (p // 1, np.zeros(len(p), np.int64)))  # 1 um per step
    assert np.all(seg.ticks >= np.abs(seg.delta).max(1))
    assert np.all(seg.ticks == 500)
