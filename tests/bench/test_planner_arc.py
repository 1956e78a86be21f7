"""Arcs planned as one block (nnik/firmware/gcode/planner_arc.py) against the float grbl oracle with
the same arc rule (nnik/bench/planner_oracle.py arc_block), on random paths: arcs of 0.2-20 mm
radius in 0.01-0.2 mm chords, corners, reversals.  Every junction <= grbl's float limit, every
speed change <= the block's acceleration, every speed in an arc <= the float arc's cap (its
centripetal limit and grbl's limit at each vertex inside); the bulk sampler equals the
sample-by-sample one; the sampled points walk the arc's chords."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from nnik.bench import planner_oracle as oracle
from nnik.bench.arc_blocks import polyline
from nnik.bench.planner_compare import compare
from nnik.bench.planner_paths import arc_block_ops
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.interpreter import run_lines
from nnik.firmware.gcode.planner import run_ops_reference
from nnik.firmware.gcode.sampler import run_ops
from tests.bench.test_planner_oracle import limits
from tests.bench.test_planner_oracle import machine as line_machine

piece = st.one_of(
    st.tuples(st.just("arc"), st.floats(200, 20000), st.floats(-360, 360), st.floats(10, 200)),
    st.tuples(st.just("line"), st.floats(20, 5000), st.floats(-180, 180)),
    st.tuples(st.just("rev"), st.floats(10, 3000)),
)


def machine(lim: dict) -> MachineConfig:
    """test_planner_oracle's machine with arc blocks (their sampler rule: no brake credit)."""
    return dataclasses.replace(line_machine(lim), arc_blocks=True)


SETTINGS = dict(deadline=None, database=None, suppress_health_check=list(HealthCheck))


@settings(max_examples=120, **SETTINGS)
@given(pieces=st.lists(piece, min_size=1, max_size=12), lim=limits, feed_share=st.floats(0.2, 1.0))
def test_arc_blocks_within_grbls_limits(pieces, lim, feed_share):
    cfg = machine(lim)
    ops = arc_block_ops(pieces, max(1000, int(cfg.max_feed_um_min * feed_share)), cfg)
    note(f"{cfg!r} arcs {sum(op[0] == 'arc' for op in ops)}")
    r = compare(ops, cfg)
    for key in ("junction", "accel", "arc_cap"):
        assert r[key].size == 0 or r[key].max() <= 1.0 + 1e-12, (key, r[key].max())


@settings(max_examples=60, **SETTINGS)
@given(pieces=st.lists(piece, min_size=1, max_size=8), lim=limits)
def test_arc_blocks_bulk_sampler_is_the_reference_and_walks_the_chords(pieces, lim):
    cfg = machine(lim)
    ops = arc_block_ops(pieces, cfg.max_feed_um_min, cfg)
    st_bulk, st_ref = run_ops(ops, cfg), run_ops_reference(ops, cfg)
    assert st_bulk == st_ref
    # each sampled point lies on the polyline of the block ends and chord ends (within 1 um)
    V = polyline(ops)
    a, b = V[:-1], V[1:]
    d = b - a
    n2 = np.maximum((d ** 2).sum(1), 1e-12)
    for p in st_ref.planned[:: max(1, len(st_ref.planned) // 200)]:
        t = np.clip(((np.asarray(p, float) - a) * d).sum(1) / n2, 0, 1)
        dist = np.hypot(*(a + t[:, None] * d - np.asarray(p, float)).T).min()
        assert dist <= 1.5, (p, dist)


def test_a_smooth_arc_is_one_block_at_its_centripetal_limit():
    """A 20 mm radius half circle in 0.05 mm chords at a feed far above its limit: one block,
    cruising at floor(sqrt(amin r 46340 / 2^16)) (Q16), below the float sqrt(amin r / sqrt(2))."""
    cfg = MachineConfig(origin_um=(0, 0), max_feed_um_min=15_000_000, accel_um_s2=(1_000_000, 2_000_000),
                        arc_blocks=True)
    ops = arc_block_ops([("arc", 20000.0, 180.0, 50.0)], cfg.max_feed_um_min, cfg)
    assert [op[0] for op in ops] == ["arc", "flush"]
    fb = oracle.blocks_of(ops, cfg)[0][0]
    assert fb.vn == math.sqrt(1e6 / math.sqrt(2) * 20000)  # the inner vertices allow more
    vmax = max(run_ops(ops, cfg).speed) * cfg.sample_hz / 65536
    assert 0.99 * fb.vn <= vmax <= fb.vn


def test_coarse_arcs_stay_chords_and_the_interpreter_groups_g2_g3():
    """A circle in 500 um chords at 8 mm radius becomes arc operations with arc_blocks (off: the
    chords' pushes); a 1 mm radius arc cut in chords longer than r / 4 stays chords."""
    lines = ["G21 G90", "G0 X8 Y0", "G3 X-8 Y0 I-8 J0 F1500", "G0 X0 Y0", "G2 X0 Y1 I0 J0.5", "M400"]
    cfg = MachineConfig(origin_um=(0, 0))
    off = run_lines(lines, cfg).plan.ops
    on = run_lines(lines, dataclasses.replace(cfg, arc_blocks=True)).plan.ops
    assert not any(op[0] == "arc" for op in off)
    arcs = [op for op in on if op[0] == "arc"]
    assert len(arcs) == 1 and arcs[0][7] == 8000 and arcs[0][1:3] == (-8000, 0)
    pushes = [op for op in off if op[0] == "push"]
    assert list(arcs[0][6]) == [op[1:3] for op in pushes[1:1 + len(arcs[0][6])]]
    assert len([op for op in on if op[0] == "push"]) == len(pushes) - len(arcs[0][6])
