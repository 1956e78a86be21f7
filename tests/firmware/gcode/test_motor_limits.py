"""Motor limits after the IK (issue 26 item 1): on random paths with random motor limits, the
sampled path's motor speeds and accelerations, from the exact IK of every sample, stay within
[motion] motor_max_speed / motor_max_accel, on a linear CoreXY, a distorted one and a galvo.

How the samples are read.  A sample's point is taken at its exact arclength s along its block
(Planner.s, Q16 um: the sampler's own state, not the whole-um point the steppers get, whose
+-1 um would swamp an acceleration of ~1 um/sample^2), start + u s with u the block's exact
float direction, or the block's end on a stop.  Motor positions are the exact IK (mechanism.inverse)
of those points.  The discretisation, explicitly:
* speed: (q(p_k) - q(p_k-1)) / dt over every consecutive pair, corners included; by the mean
  value theorem on each straight piece it is an average of dq/dt = J u v along the pieces, so it
  is bounded by the same per-direction bound as dq/dt itself: no allowance but float rounding
  (REL);
* acceleration: (q_k+1 - 2 q_k + q_k-1) / dt^2 over triples inside one straight block (a corner's
  direction change is grbl's junction rule, not a block's acceleration; a stop lands short of a
  full sample, its step to rest is the Cartesian oracle's case): by Taylor it is J u (c2 - c1) +
  u'H u (c1^2 + c2^2) / 2 + O(c^3), within (|J0 u| + delta) acc + K vmax^2 but for the third-order
  term, which the margins of nnik.machine.motor_limits (K x 1.1, delta + K x half a grid cell)
  cover; allowance REL only.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from nnik.bench.planner_paths import path_ops
from nnik.errors import NnikError
from nnik.firmware.config import default_machine
from nnik.firmware.gcode.planner import Planner
from nnik.machine.motor_limits import _to_rad, jacobian_bounds
from nnik.machine.scenario import Scenario

ROOT = Path(__file__).resolve().parents[3]
REL = 1e-6


def scenario(name: str, motion: dict, linear: bool = False) -> Scenario:
    p = ROOT / "datasets" / f"{name}.toml"
    raw = tomllib.loads(p.read_text())
    if linear:
        raw["mechanism"].pop("distortion", None)
    raw["motion"] = {**raw.get("motion", {}), **motion}
    return Scenario.from_dict(raw, str(p), p.parent)


def natural(name: str, linear: bool) -> tuple[float, float]:
    """The motors' largest speed and acceleration (user units) at the scenario's feed and accel."""
    scn = scenario(name, {}, linear)
    J0, delta, _ = jacobian_bounds(scn.mechanism, scn.workspace)
    g = float(np.abs(J0).sum(axis=1).max() + delta.max())  # rad/mm
    rad = _to_rad(scn.actuator, 1.0)
    return g * scn.motion["max_feed_mm_min"] / 60 / rad, g * scn.motion["accel_x_mm_s2"] / rad


def sampled_points(ops, cfg) -> tuple[list, list, list]:
    """Per sample: its exact point (um, machine less origin), its block's push index, stop."""
    pl, pts, blk, stops = Planner(cfg), [], [], []

    def sample():
        pl.sample()
        stop = pl.v == 0 and pl.s == 0
        b = pl.q[0] if pl.q and not stop else None
        if b is None:
            pts.append(np.array(pl.start, dtype=float))
            blk.append(-1)
        else:
            d = np.array(b.end, dtype=float) - np.array(pl.start, dtype=float)
            pts.append(np.array(pl.start, dtype=float) + d / np.hypot(*d) * (pl.s / 65536.0))
            blk.append(b.index)
        stops.append(stop)

    for op in ops:
        if op[0] == "push":
            while pl.ready(False):
                sample()
            pl.push(op[1], op[2], op[3], op[4], op[5])
        else:
            while pl.ready(True):
                sample()
    while pl.ready(True):
        sample()
    return pts, blk, stops


piece = st.one_of(
    st.tuples(st.just("line"), st.floats(20, 8000), st.floats(-180, 180)),
    st.tuples(st.just("arc"), st.floats(500, 20000), st.floats(-360, 360), st.floats(10, 200)),
    st.tuples(st.just("rev"), st.floats(10, 3000)),
)
MACHINES = [("corexy_nonlinear", True), ("corexy_nonlinear", False), ("galvo_cba2012", False)]


@pytest.mark.parametrize("name,linear", MACHINES, ids=["corexy_linear", "corexy_nonlinear", "galvo"])
@settings(max_examples=25, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(pieces=st.lists(piece, min_size=1, max_size=12), fv=st.floats(0.15, 1.5), fa=st.floats(0.15, 1.5),
       split=st.floats(0.5, 2.0), feed_share=st.floats(0.3, 1.0))
def test_motor_speed_and_acceleration_within_the_limits_after_the_ik(name, linear, pieces, fv, fa, split, feed_share):
    vn, an = natural(name, linear)
    speed, accel = [fv * vn, fv * vn * split], [fa * an, fa * an / split]
    try:
        scn = scenario(name, {"motor_max_speed": speed, "motor_max_accel": accel}, linear)
    except NnikError as exc:  # limits the firmware cannot run: one clear line, as the CLI prints it
        assert "motor" in str(exc)
        return
    cfg = default_machine(scn)
    ops = path_ops(pieces, max(1000, int(cfg.max_feed_um_min * feed_share)))
    pts, blk, stops = sampled_points(ops, cfg)
    if len(pts) < 3:  # a path of no length
        return
    mm = (np.array(pts) + np.array(cfg.origin_um)) / 1000.0
    q = scn.mechanism.inverse(mm)
    hz = cfg.sample_hz
    lim_v = np.array([_to_rad(scn.actuator, v) for v in speed])
    lim_a = np.array([_to_rad(scn.actuator, a) for a in accel])
    note(f"{cfg.motor_rows} vc {cfg.motor_vc_um_s}")
    v = np.abs(np.diff(q, axis=0)) * hz
    assert (v <= lim_v * (1 + REL)).all(), (v / lim_v).max()
    b = np.array(blk)
    s = np.array(stops)
    inside = (b[:-2] == b[1:-1]) & (b[1:-1] == b[2:]) & (b[1:-1] >= 0) & ~s[:-2] & ~s[1:-1] & ~s[2:]
    a = np.abs(q[2:] - 2 * q[1:-1] + q[:-2]) * hz * hz
    assert (a[inside] <= lim_a * (1 + REL)).all(), (a[inside] / lim_a).max()
    note(f"max speed/limit {(v / lim_v).max():.4f}, accel/limit {(a[inside] / lim_a).max() if inside.any() else 0:.4f}")


def test_bad_motor_limits_get_one_clear_error():
    for bad in ({"motor_max_speed": -1}, {"motor_max_accel": "fast"}, {"motor_max_speed": [1, 2, 3]},
                {"motor_max_accel": 1e-3}, {"motor_max_speed": math.inf}):
        with pytest.raises(NnikError, match=r"\[motion\] motor_max_"):
            scenario("corexy_nonlinear", bad)

    with pytest.raises(NnikError, match=r"\[motion\] motor_max_sped: unknown key .*motor_max_accel, motor_max_speed"):
        scenario("corexy_nonlinear", {"motor_max_sped": 5000})


def test_no_motor_limits_no_motor_defines():
    cfg = default_machine(scenario("corexy_nonlinear", {}))
    assert not cfg.motor_rows and not any(k.startswith("NNIK_GC_M0") or k.startswith("NNIK_GC_MOTOR")
                                          for k in cfg.defines())


@pytest.mark.parametrize("name,linear", MACHINES, ids=["corexy_linear", "corexy_nonlinear", "galvo"])
@settings(max_examples=40, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(fv=st.floats(0.15, 1.5), fa=st.floats(0.15, 1.5), split=st.floats(0.5, 2.0),
       moves=st.lists(st.tuples(st.integers(-300_000, 300_000), st.integers(-300_000, 300_000)), min_size=1, max_size=20))
def test_every_block_gets_at_least_twice_the_brake_credit(name, linear, fv, fa, split, moves):
    """The sampler's brake test credit (MachineConfig.brake_alpha_q16, NNIK_PL_ALPHA) is at most half
    of every block's acceleration, after the motors' caps too: its safety argument needs it
    (nnik_plan.c brake_acc())."""
    vn, an = natural(name, linear)
    try:
        scn = scenario(name, {"motor_max_speed": [fv * vn, fv * vn * split], "motor_max_accel": [fa * an, fa * an / split]},
                       linear)
    except NnikError:
        return
    cfg = default_machine(scn)
    pl = Planner(cfg)
    assert pl.alpha == cfg.brake_alpha_q16 > 0
    for dx, dy in moves:
        pl.push(pl.last[0] + dx, pl.last[1] + dy, cfg.max_feed_um_min, 0, 0)
        if pl.q:
            assert pl.q[-1].acc >= 2 * pl.alpha, (pl.q[-1].acc, pl.alpha)
        del pl.q[:-1]
