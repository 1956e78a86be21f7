"""Issue 26 item 3: the tool in step with the shaped head, on the head's path (the shaped points
the chip hands the IK), with every shaper and none, on every shipped machine and random ones.

* Dashes (cuts and travels in line, grbl laser mode: no stop between them): each switch on and
  off lands where the shaped head passes the cut's start and end, within the step of the segment
  it falls on (nnik.firmware.gcode.tool_sync), and no tool-on sample lies outside a cut.
* Corners: on random polylines of cuts and travels the head leaves the path at corners (the
  shaper rounds them), so the head's place along the path is its shaped arc length
  sum_k A_k s(t - d_k), computed here in floats from the commanded geometry; the tool is on
  exactly where that falls in a cut, but for samples within one step (plus rounding) of a cut's
  end.  This, not the head's Euclidean distance to the cut's end, is the measure at a corner:
  the shaped head cuts the corner and never passes through it (measured: a diagonal travel to
  (10, 10) mm then a cut along X at 1,500 mm/min, 1 kHz, shaped for 25 Hz, zeta 0.1: the head
  passes 90 um from the corner with ZVD, 141 um with 2hump_ei, 191 um with 3hump_ei, against
  34-39 um steps), so "where the head passes the corner" has no point on the path to switch at,
  while its arc-length place is the one the chip's tool channel tracks (nnik_shaper.h) and
  coincides with the Euclidean one along a line (the dash tests).
"""

from __future__ import annotations

import os
import types
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from nnik.dynamics.shapers import KINDS
from nnik.firmware.config import MachineConfig, default_machine, shaper_taps
from nnik.firmware.gcode.motion import interpret
from nnik.firmware.gcode.planner import duty_of
from nnik.firmware.gcode.sampler import run_ops
from nnik.firmware.gcode.tool_sync import ROUND_UM, cut_runs, switches
from nnik.machine.scenario import load_scenario

DATASETS = Path(__file__).resolve().parents[3] / "datasets"
SHIPPED = sorted(p.stem for p in DATASETS.glob("*.toml"))
ALL = ("none",) + KINDS


def shaped_stream(lines, cfg):
    plan = interpret(lines, cfg)
    s = run_ops(plan.ops, cfg)
    assert max(s.moved, default=0) <= max(cfg.vn_max_q16, *cfg.acc_q16)  # MachineConfig.progress_shift's bound
    seg = types.SimpleNamespace(ends_um=np.asarray(s.shaped, float).reshape(-1, 2), duty=duty_of(s, cfg),
                                block=np.asarray(s.block), kind=np.asarray(s.kind),
                                planned_um=np.asarray(s.planned, float).reshape(-1, 2))
    return plan, seg


def with_shaper(cfg: MachineConfig, kind: str, f: float, zeta: float) -> MachineConfig:
    if kind == "none":
        return cfg
    return replace(cfg, shaper=kind, shaper_taps=shaper_taps(kind, {"f_hz": (f, f), "zeta": (zeta, zeta)},
                                                             cfg.sample_hz))


def dashes(angle: float, pieces: list[tuple[float, bool]], feed: float, power: int) -> list[str]:
    c, s = np.cos(angle), np.sin(angle)
    out, at = ["G21 G90", "M3 S0"], 0.0
    for length, cut in pieces:
        at += length
        out.append(f"{'G1' if cut else 'G0'} X{at * c:.3f} Y{at * s:.3f} S{power if cut else 0} F{feed:.0f}")
    return out + ["M5"]


def assert_switches_within_a_step(plan, seg, cfg):
    sw = switches(plan, seg, cfg)
    assert len(sw) == len(cut_runs(plan.tool, cfg.tool_off_duty)) > 0
    covered = np.zeros(len(seg.duty), bool)
    for s in sw:
        assert s["on_at"] is not None, s
        assert abs(s["lead_um"]) <= s["on_step_um"] + ROUND_UM, s
        assert abs(s["lag_um"]) <= s["off_step_um"] + ROUND_UM, s
        covered[s["on_at"]:s["off_after"] + 1] = True
    on = (seg.duty != cfg.tool_off_duty) & (seg.kind == 0)
    assert not (on & ~covered).any()  # never on along a travel


def machine(name: str) -> MachineConfig:
    return replace(default_machine(load_scenario(DATASETS / f"{name}.toml")), tool="laser", bounds_um=None)


piece = st.tuples(st.floats(0.8, 6.0), st.booleans())


@pytest.mark.parametrize("name", SHIPPED)
@pytest.mark.parametrize("kind", ALL)
@settings(max_examples=6, deadline=None)
@given(angle=st.floats(0, 2 * np.pi), pieces=st.lists(piece, min_size=3, max_size=8), feed=st.floats(300, 6000),
       f=st.floats(40, 90), zeta=st.floats(0.0, 0.2))
def test_dashes_switch_where_the_shaped_head_passes_on_every_shipped_machine(name, kind, angle, pieces, feed, f, zeta):
    pieces = pieces + [(2.0, True), (2.0, False)]
    cfg = with_shaper(machine(name), kind, f, zeta)  # 40 Hz and up: every shaper fits the SRAM at 1 kHz
    plan, seg = shaped_stream(dashes(angle, pieces, feed, 1000), cfg)
    assert_switches_within_a_step(plan, seg, cfg)


@settings(max_examples=40, deadline=None)
@given(kind=st.sampled_from(ALL), hz=st.sampled_from([500, 1000, 2000]), acc=st.floats(300, 8000),
       feed=st.floats(300, 6000), jd=st.floats(0.005, 0.1), f=st.floats(20, 90), zeta=st.floats(0.0, 0.2),
       angle=st.floats(0, 2 * np.pi), pieces=st.lists(piece, min_size=3, max_size=8))
def test_dashes_on_random_machines(kind, hz, acc, feed, jd, f, zeta, angle, pieces):
    base = MachineConfig(origin_um=(0, 0), tool="laser", sample_hz=hz, accel_um_s2=(int(acc * 1000),) * 2,
                         junction_dev_um=int(jd * 1000), max_feed_um_min=6_000_000)
    try:
        cfg = with_shaper(base, kind, f, zeta)
    except ValueError:  # a shaper this machine cannot hold (delay, SRAM): refused with one line elsewhere
        return
    plan, seg = shaped_stream(dashes(angle, pieces + [(2.0, True), (2.0, False)], feed, 700), cfg)
    assert_switches_within_a_step(plan, seg, cfg)


def commanded_arc(plan, seg) -> tuple[np.ndarray, np.ndarray]:
    """(arc length along the commanded path of every sample's planned point, cumulative length
    at each block's end)."""
    ends = np.asarray(plan.ends, float).reshape(-1, 2)
    starts = np.vstack([[0.0, 0.0], ends[:-1]])
    cum = np.cumsum(np.hypot(*(ends - starts).T))
    blk = seg.block
    s = np.zeros(len(blk))
    ok = blk >= 0
    b = blk[ok]
    s[ok] = cum[b] - np.hypot(*(ends[b] - seg.planned_um[ok]).T)
    last = np.maximum.accumulate(np.where(ok, np.arange(len(blk)), -1))
    s[~ok] = s[np.maximum(last[~ok], 0)]  # the tail and rests stay where the plan stopped
    return s, cum


@settings(max_examples=int(os.environ.get("NNIK_TOOL_CORNERS", 60)), deadline=None)
@example(kind="2hump_ei", hz=1000, f=25.0, zeta=0.1, pts=[(10.0, 10.0, False), (20.0, 10.0, True)], feed=1500.0)
@example(kind="3hump_ei", hz=500, f=25.0, zeta=0.119140625, feed=2925.0,  # the planned step at the edge, not the shaped one
         pts=[(2.0, 4.0, False), (11.2734375, 0.0, False), (9.7265625, 0.96875, False), (0.0, 5.0, True)])
@given(kind=st.sampled_from(ALL), hz=st.sampled_from([500, 1000]), f=st.floats(25, 80), zeta=st.floats(0.0, 0.2),
       pts=st.lists(st.tuples(st.floats(-20, 20), st.floats(-20, 20), st.booleans()), min_size=3, max_size=12),
       feed=st.floats(600, 6000))
def test_at_corners_the_tool_follows_the_shaped_arc_length(kind, hz, f, zeta, pts, feed):
    try:
        cfg = with_shaper(MachineConfig(origin_um=(0, 0), tool="laser", sample_hz=hz), kind, f, zeta)
    except ValueError:  # a shaper this machine cannot hold: refused with one line elsewhere
        return
    lines = ["G21 G90", "M3 S0"] + [f"{'G1' if c else 'G0'} X{x:.3f} Y{y:.3f} S{900 if c else 0} F{feed:.0f}"
                                    for x, y, c in pts] + ["M5"]
    plan, seg = shaped_stream(lines, cfg)
    if not plan.ends:
        return
    samp = np.flatnonzero(seg.kind == 0)
    s, cum = commanded_arc(plan, seg)
    s = plan_s = s[samp]
    if cfg.shaper_taps:
        amps, delays = cfg.shaper_taps[0]
        hist = np.concatenate([np.zeros(max(delays)), s])
        s = sum(A * hist[max(delays) - d:len(hist) - d] for A, d in zip(amps, delays)) / 32768.0
    starts = np.concatenate([[0.0], cum[:-1]])
    runs = cut_runs(plan.tool, cfg.tool_off_duty)
    edges = np.array([starts[a] for a, _ in runs] + [cum[b] for _, b in runs])
    inside = np.zeros(len(s), bool)
    for a, b in runs:
        inside |= (s > starts[a]) & (s <= cum[b])
    on = seg.duty[samp] != cfg.tool_off_duty
    wrong = np.flatnonzero(on != inside)
    if len(wrong) and len(edges):
        gap = np.abs(s[wrong, None] - edges[None, :])
        near, edge = gap.min(1), edges[gap.argmin(1)]
        # The chip shapes the planner's own path length (nnik_pl_sample_t.moved) in units of
        # 2^(PSH - 16) um, and sample n takes the tool of the first planned sample m at or past
        # the shaped head's place: n is wrong only while its place and the edge lie in one
        # planned step (Q[m - 1], Q[m]], so within the planned step across the edge (either one
        # where the edge is within the rounding of a sample's end), plus the rounding: the
        # whole-um planned points here, the units' floor (one each side).
        unit = 2.0 ** (cfg.progress_shift - 16)
        rnd = ROUND_UM + 2 * unit
        plan_step = np.diff(np.concatenate([[0.0], plan_s, [plan_s[-1]]]))
        k = np.searchsorted(plan_s, np.stack([edge - rnd, edge + rnd]), side="left")
        bound = plan_step[k].max(0)
        assert (near <= bound + rnd).all(), (wrong, near, bound)
