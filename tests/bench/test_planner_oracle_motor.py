"""The integer planner against the float grbl oracle with motor limits (issue 26 item 1): the
oracle applies the same motor rows (nnik.bench.planner_oracle.motor_limit, grbl's per-axis rule on
the motor axes), so junction speeds and per-sample speed changes compare like with like."""

from __future__ import annotations

from dataclasses import replace

from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from nnik.bench.planner_compare import compare
from nnik.bench.planner_paths import path_ops
from nnik.firmware.config import MachineConfig
from nnik.machine import ranges

piece = st.one_of(
    st.tuples(st.just("line"), st.floats(20, 5000), st.floats(-180, 180)),
    st.tuples(st.just("arc"), st.floats(200, 20000), st.floats(-360, 360), st.floats(10, 200)),
    st.tuples(st.just("rev"), st.floats(10, 3000)),
)
# CoreXY's rows (a = x + y, b = x - y), a distorted machine's (a margin d), a galvo-like diagonal one
rows = st.sampled_from([((32768, 32768, 0), (32768, -32768, 0)), ((32300, 32500, 200), (32600, -32400, 150)),
                        ((0, 29601, 3169), (-28009, 0, 4761))])


@settings(max_examples=40, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(pieces=st.lists(piece, min_size=1, max_size=15), r=rows, v=st.integers(5, 150), a=st.integers(300, 5000),
       vc=st.sampled_from([0, 40_000]), blocks=st.integers(2, 16), hz=st.sampled_from([500, 1000]))
def test_motor_limited_planner_within_the_float_oracle(pieces, r, v, a, vc, blocks, hz):
    cfg = MachineConfig(origin_um=(0, 0), accel_um_s2=(3_000_000, 3_000_000), max_feed_um_min=6_000_000,
                        sample_hz=hz, plan_blocks=blocks)
    cfg = replace(cfg, motor_rows=tuple((*c, v * 1000, a * 1000) for c in r), motor_vc_um_s=vc)
    if any(ranges.motor_problem(v * 1000, a * 1000, hz) for _ in r):
        return
    note(repr(cfg.motor_rows))
    res = compare(path_ops(pieces, cfg.max_feed_um_min), cfg)
    assert res["junction"].size == 0 or res["junction"].max() <= 1.0 + 1e-12, res["junction"].max()
    assert res["accel"].size == 0 or res["accel"].max() <= 1.0 + 1e-12, res["accel"].max()
