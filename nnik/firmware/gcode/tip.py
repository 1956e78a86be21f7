"""Where the tool really goes: the tip of each belt axis (nnik.dynamics.axis) driven by the step
stream the firmware emits, and the figures issue 18 asks of it.

The base is the exact forward kinematics of the motor counts after every stepper tick, held over
the tick (the steps are the firmware's: the Python model's events, which the chip matches bit
for bit).  The tip follows through each Cartesian axis's spring-damper, with TAIL_S of rest
after the job.  Reported (um):
  * contour: the tip's distance to the programmed path (Koren: to its move or the neighbours);
  * dynamics: |tip - base|, what the belts add to the kinematic error;
  * ringing: the tip's peak distance to the path 20-200 ms after each stop or corner of the
    planned motion (nnik.dynamics.ringing), the windows shifted by the shaper's delay (its
    centroid: the shaped command stops that much later);
  * its dynamic part: the peak of |tip's distance - the steps' own distance| in the same windows
    (what the belts add; the steps' own, the floor, is IK + rounding + chord + the microstep);
  * the tip's lag behind the head at every tool switch (tool_switch_lag_um), beside the head's
    own lead at the switch (the job's tool.switches).
"""

from __future__ import annotations

import numpy as np

from nnik.dynamics.ringing import TAIL_S, event_index, ringing, tip_track
from nnik.firmware.gcode.contour import _stats, path_dist_um, segment_moves, units_to_mm
from nnik.firmware.gcode.tool_sync import switches


def counts_per_tick(seg, ev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(counts (T, 2) after every tick of the job, segment (T,) of each tick), segments back to
    back from the start command."""
    ticks = np.asarray(seg.ticks, dtype=np.int64)
    total = int(ticks.sum())
    start = np.concatenate([[0], np.cumsum(ticks)[:-1]])
    inc = np.zeros((total, 2), np.int64)
    if len(ev):
        at = start[ev[:, 0]] + ev[:, 1] - 1
        np.add.at(inc, (at, ev[:, 2]), np.where(ev[:, 3] == 1, 1, -1))
    counts = seg.steps[0] + np.cumsum(inc, axis=0)
    return counts, np.repeat(np.arange(len(ticks)), ticks)


def shaper_delay_s(cfg) -> float:
    """How long after the planned motion the shaped command does the same: the shaper's
    centroid (sum A_i d_i), the larger of the two axes'; 0 without a shaper."""
    taps = getattr(cfg, "shaper_taps", ()) or ()
    return max((sum(a * d for a, d in zip(amps, delays)) / 32768 / cfg.sample_hz for amps, delays in taps), default=0.0)


def switch_lag(plan, seg, cfg, seg_start: np.ndarray, dyn_um: np.ndarray) -> dict:
    """The belt tip's distance behind the head (um) at every tool switch on and off (the first
    tick of the first on and of the first off segment: nnik.firmware.gcode.tool_sync)."""
    if getattr(seg, "block", None) is None:
        return _stats(np.zeros(0))
    at = [s[k] for s in switches(plan, seg, cfg) if s.get("on_at") is not None for k in ("on_at", "off_after")]
    ticks = np.minimum(seg_start[np.asarray(at, dtype=np.int64) + np.tile([0, 1], len(at) // 2)], len(dyn_um) - 1)
    return _stats(dyn_um[ticks] if len(at) else np.zeros(0))


def tip_report(scn, cfg, plan, seg, ev: np.ndarray, dyn: dict, moves=None, keep_track: bool = False) -> dict:
    """The tip's contour error, the dynamics' share and the ringing of a job's step stream.
    The ringing windows start at the stops and corners of the planner's samples before any
    shaping (seg.planned_um).  moves: the programmed moves to measure against (default the
    plan's; a precompensated job is measured against the job it came from), with the move of
    each segment in seg.move."""
    origin_mm = np.asarray(cfg.origin_um, dtype=np.float64) / 1000.0
    counts, seg_of = counts_per_tick(seg, ev)
    if not len(counts):
        return {"contour_um": _stats(np.zeros(0)), "dynamics_um": _stats(np.zeros(0)),
                "ringing_um": {"max": 0.0, "mean": 0.0, "n": 0}}
    base = units_to_mm(scn, counts)
    tip = tip_track(base, cfg.tick_hz, dyn)
    tail = len(tip) - len(base)
    seg_move = seg.move if getattr(seg, "move", None) is not None else segment_moves(plan)
    idx = seg_move[np.concatenate([seg_of, np.full(tail, seg_of[-1])])]
    dev = path_dist_um(tip, idx, plan.moves if moves is None else moves, origin_mm)
    held = np.concatenate([base, np.repeat(base[-1:], tail, 0)])
    dyn_um = np.hypot(*(tip - held).T) * 1000.0
    base_dev = path_dist_um(held, idx, plan.moves if moves is None else moves, origin_mm)
    seg_start = np.concatenate([[0], np.cumsum(seg.ticks)])
    at = seg_start[event_index(np.asarray(seg.planned_um, float) / 1000.0) + 1] / cfg.tick_hz
    at = at + shaper_delay_s(cfg)
    out = {"contour_um": _stats(dev), "dynamics_um": _stats(dyn_um),
           "ringing_um": ringing(dev, cfg.tick_hz, at),
           "ringing_dynamic_um": ringing(np.abs(dev - base_dev), cfg.tick_hz, at),
           "ringing_floor_um": ringing(base_dev, cfg.tick_hz, at),
           "tail_s": TAIL_S,
           "model": {"f_hz": list(dyn["f_hz"]), "zeta": list(dyn["zeta"])}}
    out["tool_switch_lag_um"] = switch_lag(plan, seg, cfg, seg_start, dyn_um)
    if keep_track:
        out["track"] = {"tip_mm": tip, "base_mm": held, "error_um": dev,
                        "time_s": np.arange(len(tip)) / cfg.tick_hz}
    return out
