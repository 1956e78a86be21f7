"""The firmware's motion logic in Python: segment ends, arcs, modes, errors (no IK needed)."""

from __future__ import annotations

import math
from math import ceil, isqrt

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.geometry import r_centre
from nnik.firmware.gcode.motion import Interpreter, interpret, plan_steps

CFG = MachineConfig(origin_um=(0, 0), seg_um=500)


def ends(lines, cfg=CFG):
    plan = interpret(lines, cfg)
    assert all(r == "ok" for r in plan.replies), plan.replies
    return plan, np.asarray(plan.ends)


def test_a_line_is_one_planner_block_ending_exactly():
    plan, e = ends(["G1 X10 Y3.3 F600", "G1 X10 Y3.3", "G0 X0 Y0"])
    assert e.tolist() == [[10000, 3300], [0, 0]]  # the line to where it stands adds nothing
    assert plan.feed == [600000, CFG.max_feed_um_min]
    assert [op[0] for op in plan.ops] == ["push", "push"]  # the job's end flushes in plan_steps


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


@pytest.mark.parametrize("line, code, detail", [
    ("G1 X1 I2", 36, "I"),  # grbl: unused words
    ("G2 X1 Y1", 35, ""),  # no in-plane offset
    ("G2 Z1 I1", 32, ""),  # no in-plane axis word
    ("G2 X12 R4.9", 33, "longer than 2|R|"),
    ("G3 X1 Y1 R-1", 33, "ends at its start"),
    ("G2 X2 I1 R1", 36, "I"),  # R wins, I is unused
    ("G1 X2 R1", 36, "R"),
    ("G2 X2 R0", 33, "R0"),
    ("G2 X10 I1", 33, "off the circle"),
    ("G2 X1 I0 J0", 33, "radius zero"),
    ("G1 X1 F0.5", 22, "below 1 mm/min"),
    ("G80 X1", 31, ""),
    ("G0 G28 X1", 24, ""),
    ("G53 G2 X1 I1", 30, ""),
])
def test_bad_lines_move_nothing(line, code, detail):
    it = Interpreter(CFG)
    it.line("G1 X1 Y1")
    n = len(it.plan.ends)
    reply = it.line(line)
    assert reply == f"error:{code}" and detail in it.last_error
    assert len(it.plan.ends) == n and tuple(it.mp[:2]) == (1000, 1000)


def test_coordinates_beyond_the_limit_are_refused():
    it = Interpreter(CFG)
    for _ in range(10):
        reply = it.line("G20 G91 G0 X9999")
    assert reply == "error:33"


def test_a_sample_is_its_ticks_unless_the_steps_need_more():
    plan, _ = ends(["G1 X10 F600"])
    seg = plan_steps(plan, CFG, lambda p: (p // 40, np.zeros(len(p), np.int64)))  # 40 um per step
    assert np.all(seg.ticks == CFG.tick_hz // CFG.sample_hz) and seg.overspeed == 0
    assert seg.ticks.sum() > 1000 * 10 * 10000 // 10000  # 10 mm at 10 mm/s: over a second of samples
    fast, _ = ends(["G0 X10"])
    seg = plan_steps(fast, CFG, lambda p: (p // 1, np.zeros(len(p), np.int64)))  # 1 um per step
    assert np.all(seg.ticks == np.maximum(10, np.abs(seg.delta).max(1)))
    assert seg.overspeed == int((np.abs(seg.delta).max(1) > 10).sum()) > 0  # 50 um per 10-tick sample


@settings(max_examples=400, deadline=None, database=None)
@given(x=st.integers(-(2**29 - 2), 2**29 - 2), y=st.integers(-(2**29 - 2), 2**29 - 2), extra=st.integers(0, 2**28),
       long_way=st.booleans(), ccw=st.booleans())
def test_r_centre_lies_at_r_from_both_ends_on_the_asked_side(x, y, extra, long_way, ccw):
    """Over every chord the firmware can meet (|x|, |y| < 2^29 um) and every R up to 9999 in, the
    integer centre is within 2.5 um of the exact one (so the arc passes the end check) and on the
    side that makes the arc short (or long for negative R) in the asked direction."""
    d = math.hypot(x, y)
    rad = min(math.ceil(d / 2) + extra, 254_000_000)
    assume(d > 0 and d <= 2 * rad)
    i, j = r_centre(x, y, -rad if long_way else rad, ccw)
    h = math.sqrt(max(rad * rad - d * d / 4, 0.0))
    side = 1 if ccw != long_way else -1  # left of the chord
    exact = (x / 2 - side * h * y / d, y / 2 + side * h * x / d)
    assert math.hypot(i - exact[0], j - exact[1]) <= 2.5
    assert abs(math.hypot(i, j) - rad) <= 2.5 and abs(math.hypot(i - x, j - y) - rad) <= 2.5
    if h > 3:
        assert (x * j - y * i > 0) == (side > 0)


def test_r_arcs_short_long_and_semicircle():
    plan, e = ends(["G0 X10", "G3 X0 Y10 R10", "G3 X10 Y0 R-10", "G2 X0 Y0 R5", "G2 X10 R4.9999"])
    quarter, three_quarters, half, half_at_tol = plan.moves[1:]
    assert quarter.center == (0, 0) and three_quarters.center == (0, 0)
    assert three_quarters.n_seg == 3 * quarter.n_seg
    assert half.center == (5000, 0) and half_at_tol.center == (5000, 0)  # 0.1 um short of 2R: within the tolerance


@settings(max_examples=300, deadline=None, database=None)
@given(rows=st.lists(st.tuples(st.integers(-(2**25) + 1, 2**25 - 1), st.integers(-(2**25) + 1, 2**25 - 1)),
                     min_size=1, max_size=50), square=st.integers(0, 2**24))
def test_row_square_roots_are_exact_floors(rows, square):
    from math import isqrt

    from nnik.firmware.gcode.motion import isqrt_rows

    d = np.asarray(rows + [(square, 0), (square, 1), (-square, -1)], dtype=np.int64)
    assert isqrt_rows(d).tolist() == [isqrt(int(a * a + b * b)) for a, b in d.tolist()]


def test_a_negative_p_is_a_g5_offset_never_a_dwell():
    """With G5 modal, G5's own P may be negative; G4's may not (it was a negative rest)."""
    it = Interpreter(CFG)
    assert it.line("G5 I1 J0 P-1 Q0 X3 Y1") == "ok" and it.line("P-1 Q0 X5 Y1") == "ok"
    assert it.line("G4 P-1") == "error:4" and it.line("G10 L2 P-1 X0") == "error:4"
    assert not it.plan.dwell
