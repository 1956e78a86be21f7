"""The planner and sampler (nnik/firmware/gcode/planner.py, the model of nnik_plan.c): the
trapezoid of a lone line, the per-sample acceleration bound on each axis, junction speeds under
the deviation rule, the stop at rest on the end point, and samples on the programmed path."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.bench.planner_oracle import junction_limit
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.motion import interpret
from nnik.firmware.gcode.planner import Planner
from nnik.firmware.gcode.sampler import run_ops

CFG = MachineConfig(origin_um=(0, 0))  # 1000 mm/s^2 = 1 um/sample^2 = 65536 Q16; 3000 mm/min = 50 um/sample


def stream(lines, cfg=CFG):
    plan = interpret(lines, cfg)
    assert all(r == "ok" for r in plan.replies), plan.replies
    st_ = run_ops(plan.ops, cfg)
    return plan, st_, np.asarray(st_.planned, dtype=np.int64).reshape(-1, 2), np.asarray(st_.speed, dtype=np.int64)


def test_a_lone_line_is_a_trapezoid_with_exact_sample_counts():
    _, s, p, v = stream(["G1 X100 F3000"])
    acc, vn = CFG.acc_q16[0], CFG.vn_max_q16
    assert (acc, vn) == (65536, 50 * 65536)
    # 50 samples of acceleration, one acc each, the 50th reaching the feed exactly
    assert v[:50].tolist() == [acc * k for k in range(1, 51)]
    cruise = np.flatnonzero(v == vn)
    assert cruise[0] == 49 and np.all(np.diff(cruise) == 1) and len(cruise) == 1950
    dec = v[cruise[-1]:]
    # deceleration: never faster than acc per sample, each sample the fastest speed the brake
    # test (the sampler's own steps down to rest, Q8 speeds) allows, found by halving between
    # hold and a whole acc down (so some steps are a part of acc); then the last um is landed
    # on: the sample's speed may be v + acc, the distance it moves is what was left, within acc
    # of the speed before and of rest
    steps = np.diff(dec[:-1])
    assert np.all((steps <= 0) & (steps >= -acc)) and (steps == -acc).sum() >= 45
    assert 0 < s.moved[-1] <= acc and v[-2] - s.moved[-1] <= acc
    assert len(v) == 2050  # the continuous trapezoid takes L / v + v / a = 2050 samples
    assert tuple(p[-1]) == (100000, 0) and np.all(np.diff(p[:, 0]) >= 0)
    # the last sample lands exactly on the end: the speeds before it cover less than the line
    assert v[:-1].sum() < 100000 * 65536 <= v.sum()


@settings(max_examples=40, deadline=None, database=None)
@given(ang=st.integers(0, 359), dist=st.integers(200, 60000), ax=st.integers(50, 5000), ay=st.integers(50, 5000),
       feed=st.integers(100, 6000))
def test_acceleration_per_axis_is_never_exceeded_on_a_line(ang, dist, ax, ay, feed):
    """Second differences of each axis' samples stay within that axis' acceleration per sample,
    plus 4 um of rounding: each point is within 2 um short of the exact one (the distance along
    the block is taken in whole um, then the point is floored), so a second difference may
    gain 2 x 2 um."""
    cfg = MachineConfig(origin_um=(0, 0), accel_um_s2=(ax * 1000, ay * 1000), max_feed_um_min=6_000_000)
    x, y = dist * math.cos(math.radians(ang)) / 1000, dist * math.sin(math.radians(ang)) / 1000
    _, s, p, v = stream([f"G1 X{x:.3f} Y{y:.3f} F{feed}"], cfg)
    pts = np.vstack([[0, 0], p])
    a2 = np.abs(np.diff(pts, n=2, axis=0))
    per_sample = np.array([ax, ay]) * 1000 / cfg.sample_hz**2
    assert np.all(a2 <= per_sample + 4), (a2.max(0), per_sample)
    dv = np.abs(np.diff(np.concatenate([[0], v])))
    end = np.asarray(_.ends[-1], dtype=float)
    u = np.abs(end) / np.hypot(*end)
    path_acc = min(a / ui for a, ui in zip(cfg.acc_q16, u) if ui > 0)  # the block's: a_axis / |u_axis|
    assert dv.max() <= path_acc + 1  # speed steps: at most the block's acceleration per sample
    assert v[-1] > 0 and len(v) < 10 * dist + 100  # finite: it ends


@pytest.mark.parametrize("turn", [10, 30, 45, 90, 120, 170, 180])
def test_junction_speed_follows_the_deviation_rule(turn):
    """An X line then a line turned by `turn` degrees: the speed of the sample that crosses the
    corner is at most grbl's v_j = sqrt(a_j d sin(t/2) / (1 - sin(t/2))) (a_j: the junction
    vector's axis limit, nnik.bench.planner_oracle) and at most the feed, and at least 90 % of it
    (the rule is used, not a stop); a reversal stops there."""
    x2, y2 = 20 + 20 * math.cos(math.radians(turn)), 20 * math.sin(math.radians(turn))
    _, s, p, v = stream(["G1 X20 F3000", f"G1 X{x2:.3f} Y{y2:.3f}"])
    blk = np.asarray(s.block)
    k = np.flatnonzero(blk == 1)[0]  # the first sample ending in the second block
    d = np.array([round(x2 * 1000) - 20000, round(y2 * 1000)], dtype=float)
    u1 = tuple(d / np.hypot(*d))
    vj = junction_limit((1.0, 0.0), u1, 50000.0, 50000.0, (1e6, 1e6), float(CFG.junction_dev_um)) / CFG.sample_hz
    if turn == 180:  # a stop on the corner, then the second line starts again from rest
        assert tuple(p[k - 1]) == (20000, 0) and s.moved[k - 1] <= CFG.acc_q16[0] and v[k] == CFG.acc_q16[0]
    else:  # the speed of the sample that crosses the corner
        assert v[k] / 65536 <= vj, (v[k] / 65536, vj)
        assert v[k] / 65536 >= vj * 0.9


@settings(max_examples=30, deadline=None, database=None)
@given(pts=st.lists(st.tuples(st.integers(-20000, 20000), st.integers(-20000, 20000)), min_size=1, max_size=6),
       feed=st.integers(300, 6000), arc=st.booleans())
def test_samples_lie_on_the_programmed_path_and_end_at_rest(pts, feed, arc):
    """Without a shaper every sample is on a block (a line, or an arc's chord) within 1.5 um
    (floor rounding and the Q30 unit vector), and the job ends at rest exactly on the last point."""
    lines = [f"G1 F{feed}", "X1 Y0.5"] + [f"X{x / 1000:.3f} Y{y / 1000:.3f}" for x, y in pts]
    if arc:  # a full circle: grbl needs its end written out
        lines.append(f"G2 X{pts[-1][0] / 1000:.3f} Y{pts[-1][1] / 1000:.3f} I3 J0")
    plan, s, p, v = stream(lines)
    ends = np.vstack([[0, 0], np.asarray(plan.ends).reshape(-1, 2)]).astype(float)
    a, b = ends[:-1], ends[1:]
    ab = b - a
    L2 = np.maximum((ab**2).sum(1), 1e-12)
    t = np.clip((((p[:, None, :] - a[None]) * ab[None]).sum(2)) / L2[None], 0, 1)
    d = np.linalg.norm(p[:, None, :] - (a[None] + t[..., None] * ab[None]), axis=2).min(1)
    assert d.max() <= 1.5, d.max()
    assert tuple(p[-1]) == tuple(ends[-1].astype(int)) and s.speed[-1] > 0
    assert run_ops(plan.ops, CFG).planned == s.planned  # the same operations, the same samples


def test_dwell_and_m400_stop_the_motion_first():
    _, s, p, v = stream(["G1 X5 F3000", "G4 P0.1", "G1 X10", "M400", "G1 X12"])
    kind = np.asarray(s.kind)
    r = np.flatnonzero(kind == 1)
    assert len(r) == 1 and s.rest_ticks[r[0]] == 1000
    assert tuple(s.planned[r[0] - 1]) == (5000, 0)  # at rest on the end of the first line
    # the next sample starts again from rest
    assert s.speed[r[0] + 1] == CFG.acc_q16[0]


@pytest.mark.parametrize("kw, msg", [
    ({"accel_um_s2": (0, 1000)}, r"accel_x_mm_s2: must be in \[0.245, "),
    ({"accel_um_s2": (100, 1000)}, "accel_x_mm_s2: must be in"),
    ({"sample_hz": 3000}, "sample_hz: must divide the 10000 Hz tick rate"),
    ({"junction_dev_um": 0}, "junction_deviation_mm: must be in"),
    ({"max_feed_um_min": 10**9}, "max_feed_mm_min: must be in"),
    ({"shaper": "zvd"}, "shaper taps are needed"),
    ({"shaper": "zv", "shaper_taps": (((16384, 16383), (0, 10)), ((32768,), (0,)))}, "summing to 32768"),
    ({"shaper": "zv", "shaper_taps": (((16384, 16384), (0, 200)), ((32768,), (0,)))}, "SRAM"),
    ({"shaper": "wobble", "shaper_taps": (((32768,), (0,)),) * 2}, "shaper must be one of"),
])
def test_bad_motion_settings_are_one_line(kw, msg):
    with pytest.raises(ValueError, match=msg) as exc:
        MachineConfig(origin_um=(0, 0), **kw)
    assert "\n" not in str(exc.value)


@settings(max_examples=60, deadline=None, database=None)
@given(ax=st.integers(100, 3_999), ay=st.integers(100, 3_999), hz=st.sampled_from([250, 500, 1000, 2000]),
       dx=st.integers(-500_000, 500_000), dy=st.integers(-500_000, 500_000))
def test_the_brake_credit_is_half_the_least_axis_acceleration_and_at_most_half_a_blocks(ax, ay, hz, dx, dy):
    cfg = MachineConfig(origin_um=(0, 0), sample_hz=hz, accel_um_s2=(ax * 1000, ay * 1000))
    assert cfg.brake_alpha_q16 == min(cfg.acc_q16) >> 1
    assert replace(cfg, speed_search=False).brake_alpha_q16 == 0 == replace(cfg, arc_blocks=True).brake_alpha_q16
    pl = Planner(cfg)
    pl.push(dx, dy, cfg.max_feed_um_min, 0, 0)
    assert not pl.q or pl.q[0].acc >= 2 * pl.alpha
