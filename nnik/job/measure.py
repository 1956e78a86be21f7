"""Stage 6 of a job, measure: its figures from the Python model's steps (the job's time, its peak
step rate, the tool's on length, the contour error against the programmed path; with [dynamics],
the chosen method's tip) and the chip's run against the model (steps, answers and tool changes
equal, the sample loop's share of the CPU).

SampledJob -> MeasuredJob (figures, in the JSON's order, and the arrays the plot draws);
compare_chip(CoSimulated, MeasuredJob, ...) -> the chip's figures.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nnik.dynamics.shaper_figures import axis_figures
from nnik.errors import NnikError
from nnik.files.atomic_write import write_file_atomic
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.firmware.gcode.contour import contour_report
from nnik.firmware.gcode.steps import model_tool_events
from nnik.firmware.gcode.tool_sync import summary, switches
from nnik.job.cosim import CoSimulated
from nnik.job.sample import SampledJob

SLOW_JOB_S = 60.0  # a job with more motion than this, at an average speed far below the max feed, is said
SLOW_FRACTION = 0.01  # "far below": under 1 % of the max feed on average (an F1 typo: F1 is 1/3000 of 3000)


@dataclass
class MeasuredJob:
    sampled: SampledJob
    figures: dict  # the job's JSON so far: scenario, job, gcode, machine, tool, motion, contour, dynamics
    plot: dict  # reached points, their error and time (contour_report's), for the picture
    warnings: list[str] = field(default_factory=list)

    @property
    def seconds(self) -> float:
        return self.figures["seconds"]


def tool_report(seg, cfg: MachineConfig) -> dict:
    """Tool-on (laser on, pen down) and travel length and the tool's on-time, from the segments."""
    on = seg.duty != cfg.tool_off_duty
    step = np.hypot(*np.diff(np.vstack([[0, 0], seg.ends_um]), axis=0).T)  # each segment's shaped motion, um
    return {"kind": cfg.tool, "on_mm": float(step[on].sum() / 1000.0),
            "travel_mm": float(step[~on].sum() / 1000.0), "on_s": float(seg.ticks[on].sum() / cfg.tick_hz),
            "changes": int(len(model_tool_events(seg)))}


def slow_job_warning(res: dict, cfg: MachineConfig) -> str | None:
    """One line when the job's motion takes long for its length: the co-simulation runs for as
    long (an F1 typo makes 10 mm take 600 s)."""
    t = res["motion"]["job_s"]
    mm = res["tool"]["on_mm"] + res["tool"]["travel_mm"]
    feed = cfg.max_feed_um_min / 1000.0
    if t < SLOW_JOB_S or mm / t * 60.0 >= SLOW_FRACTION * feed:
        return None
    return (f"the job moves {mm:.1f} mm in {t:.0f} s of motion, an average of {mm / t * 60.0:.3g} mm/min against the "
            f"machine's max feed of {feed:g} mm/min (a mistyped F?); the chip's co-simulation simulates every second "
            "of it")


def motion_report(seg, cfg: MachineConfig, dyn: dict | None = None) -> dict:
    """The job's time, its peak step rate against the stepper's limit (one step per tick per
    motor), the samples stretched beyond their ticks, and the settings behind them (with each
    axis's shaper and its Klipper figures, the vibration on the [dynamics] resonance dyn)."""
    samp = seg.kind == 0
    rate = np.abs(seg.delta).max(1)[samp] * cfg.tick_hz / np.maximum(seg.ticks[samp], 1) if samp.any() else np.zeros(1)
    return {"job_s": float(seg.ticks.sum() / cfg.tick_hz), "samples": int(samp.sum()),
            "peak_step_rate_hz": float(rate.max()), "step_rate_limit_hz": cfg.tick_hz,
            "overspeed_samples": seg.overspeed, "peak_speed_mm_s": float(seg.speed_um_s.max() / 1000.0) if samp.any() else 0.0,
            "sample_hz": cfg.sample_hz, "accel_mm_s2": [a / 1000.0 for a in cfg.accel_um_s2],
            "junction_deviation_mm": cfg.junction_dev_um / 1000.0, "max_feed_mm_min": cfg.max_feed_um_min / 1000.0,
            "shaper": cfg.shaper, "shaper_taps": [list(map(list, t)) for t in cfg.shaper_taps],
            "shaper_ram_bytes": cfg.shaper_ram_bytes, "plan_blocks": cfg.lookahead,
            "shaper_figures": axis_figures(cfg.shaper_design if cfg.shaper != "none" else (), dyn)}


def measure(sampled: SampledJob, warn=None) -> MeasuredJob:
    """The model's figures (NnikError: a sample clamped by the IK although the job fits); warn:
    called at once with each warning line (a job whose motion is long for its length)."""
    shaped = sampled.shaped
    parsed, cfg, seg = shaped.parsed, shaped.cfg, sampled.segments
    req, scn = parsed.request, parsed.scenario
    res = {"scenario": scn.name, "job": req.job.name, "unit": scn.unit, "gcode": parsed.summary,
           "machine": {"origin_um": list(cfg.origin_um), "seg_um": cfg.seg_um, "tick_hz": cfg.tick_hz,
                       "sample_hz": cfg.sample_hz, "shaper": cfg.shaper,
                       "tool": cfg.tool, "tool_defines": cfg.defines()},
           "tool": {**tool_report(seg, cfg), "switches": summary(switches(shaped.plan, seg, cfg))},
           "motion": motion_report(seg, cfg, scn.dynamics),
           **contour_report(scn, cfg, shaped.plan, seg, sampled.events)}
    slow = slow_job_warning(res, cfg)
    if slow:
        res["warnings"] = [slow]
        if warn is not None:
            warn(slow)
    if res["clamped"]:
        raise NnikError(f"{res['clamped']} samples outside the IK's domain although the job fits the workspace: "
                        "a bug, please report it", req.source)
    plot = res.pop("plot")
    dyn_fig = shaped.dynamics
    if dyn_fig is not None:
        chosen = dyn_fig["methods"][dyn_fig["chosen"]]
        res["dynamics"] = dyn_fig
        res["tip"] = {k: chosen[k] for k in ("contour_um", "dynamics_um", "ringing_um", "ringing_floor_um")}
    return MeasuredJob(sampled, res, plot, [slow] if slow else [])


def cpu_report(run, busy: np.ndarray, samples: int) -> dict:
    """The sample loop's share of the CPU: the busy pin (high while the sketch parses, plans,
    samples, shapes, runs the IK and queues; low while it waits for queue room or input) over the
    motion's time, from the first segment to the machine's last tick; and busy cycles per sample.
    worst_sample_cycles: the longest busy stretch inside the motion (one sample's work while the
    segment queue is full; longer than the sample period, 16,000 cycles at 1 kHz, when the chip
    computes behind the stepper), max: the longest of all (with the start's parsing and planning)."""
    first = int(run.marks[0]) if len(run.marks) else 0
    end = run.idle_cycle or run.end_cycle
    lo, hi = np.maximum(run.busy[:, 0], first), np.minimum(run.busy[:, 1], end)
    inside = np.maximum(hi - lo, 0)
    out = {"cycles_per_sample": {"mean": float(busy.sum()) / max(samples, 1), "max": int(busy.max()),
                                 "windows": int(len(busy))},
           "worst_sample_cycles": int(inside.max()) if len(inside) else 0}
    inside = float(inside.sum())
    if end > first:
        out["cpu_sample_loop"] = inside / (end - first)
    return out


def missed_samples(marks: np.ndarray, seg, cycles_per_tick: int) -> int:
    """Samples the chip computed too late: a segment that starts later than the one before it
    ends (the stepper's queue ran dry) while the head moves on both sides of the gap (a planned
    speed or a shaped move). A wait at rest (a sync, a dwell, the end) is no miss."""
    marks = np.asarray(marks, dtype=np.int64)
    n = min(len(marks), len(seg.ticks))
    if n < 2:
        return 0
    late = np.diff(marks[:n]) - seg.ticks[:n - 1].astype(np.int64) * cycles_per_tick > cycles_per_tick // 2
    moving = (np.asarray(seg.speed_q16[:n]) > 0) | (np.asarray(seg.chord[:n]) > 0)
    return int((late & moving[:-1] & moving[1:]).sum())


def write_step_counts(path: Path, steps: np.ndarray, start: np.ndarray) -> Path:
    """Each motor's count over time as the chip's pins show it: cycle, motor, dir, count after."""
    steps = np.asarray(steps, dtype=np.int64).reshape(-1, 3)
    count = np.zeros(len(steps), np.int64)
    sign = np.where(steps[:, 2] == 1, 1, -1)
    for m in range(2):
        sel = steps[:, 1] == m
        count[sel] = start[m] + np.cumsum(sign[sel])
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = np.column_stack([steps, count])
    write_file_atomic(path, "cycle,motor,dir,count\n" + ("%d,%d,%d,%d\n" * len(rows)) % tuple(rows.ravel().tolist()))
    return path


def compare_chip(co: CoSimulated, measured: MeasuredJob, out: Path) -> dict:
    """The chip's run against the model: steps, replies, tool changes; the sample loop's CPU (the
    chip's step counts go to OUTDIR/job/JOB_chip_steps.csv)."""
    sampled, res = measured.sampled, measured.figures
    seg, events, plan = sampled.segments, sampled.events, sampled.shaped.plan
    c, ev, run = dict(co.figures), co.events, co.run
    tev, want_tev = co.tool_events, model_tool_events(seg)
    stem = sampled.shaped.parsed.request.job.stem
    c["steps_csv"] = str(write_step_counts(out / f"{stem}_chip_steps.csv", run.steps, seg.steps[0]))
    same = (c["segments_started"] == res["segments"] and ev.shape == events.shape
            and bool((ev == events).all()))
    busy = (run.busy[:, 1] - run.busy[:, 0]).astype(np.float64)
    c.update({"steps": int(len(ev)), "steps_equal": same, "replies_equal": c["replies"] == plan.replies,
              "tool_changes": int(len(tev)),
              "tool_equal": tev.shape == want_tev.shape and bool((tev == want_tev).all())})
    if len(busy) and res["segments"]:
        c.update(cpu_report(run, busy, res["motion"]["samples"]))
        c["missed_samples"] = missed_samples(run.marks, seg, CLOCK_HZ // sampled.shaped.cfg.tick_hz)
    return c
