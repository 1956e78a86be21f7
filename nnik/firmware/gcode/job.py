"""`nnik job`: a G-code job through the firmware's logic in Python and on the simulated Uno.

The Python model gives every step (segment, tick, motor, direction) and the contour error;
the chip (the library's NAME_gcode sketch built with the Arduino AVR core, on simavr) must emit
the same steps, and its measured cycles per segment give the segment rate it sustains at
<= 50 % CPU. Results: OUTDIR/job/<job>.json and <job>.png.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnik.files.outdir import JOB_DIR
from nnik.progress import bar
from nnik.errors import NnikError
from nnik.firmware.gcode.contour import contour_report
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.ik_oracle import ik_oracle, load_scenario_of
from nnik.firmware.gcode.parse import split_lines
from nnik.firmware.gcode.plot import job_png
from nnik.firmware.gcode.steps import chip_events, chip_tool_events, model_events, model_tool_events

CPU_SHARE = 0.5  # of the chip for segment preparation; the rest steps, talks and waits
CLOCK_HZ = 16_000_000


MACHINE_TAG = "; nnik-machine:"
MACHINE_KEYS = {"tool": str, "s_max": int, "pen_z_um": int, "servo_up_deg": int, "servo_down_deg": int}


def job_machine(lines: list[str], cfg: MachineConfig, source: str) -> MachineConfig:
    """The tool a job is written for, from its comment lines '; nnik-machine: tool=servo
    pen_z_um=500' (the firmware reads them as comments); without one, cfg as it is."""
    from dataclasses import replace

    kw = {}
    for ln in lines:
        if not ln.startswith(MACHINE_TAG):
            continue
        for item in ln[len(MACHINE_TAG):].split():
            key, _, val = item.partition("=")
            if key not in MACHINE_KEYS:
                raise NnikError(f"unknown machine setting {key!r}; known: {', '.join(MACHINE_KEYS)}", source)
            try:
                kw[key] = MACHINE_KEYS[key](val)
            except ValueError:
                raise NnikError(f"machine setting {key} needs a {MACHINE_KEYS[key].__name__}", source) from None
    try:
        return replace(cfg, **kw)
    except ValueError as exc:
        raise NnikError(str(exc), source) from None


def tool_report(seg, cfg: MachineConfig) -> dict:
    """Tool-on (laser on, pen down) and travel length and the tool's on-time, from the segments."""
    on = seg.duty != cfg.tool_off_duty
    return {"kind": cfg.tool, "on_mm": float(seg.chord[on].sum() / 1000.0),
            "travel_mm": float(seg.chord[~on].sum() / 1000.0), "on_s": float(seg.ticks[on].sum() / cfg.tick_hz),
            "changes": int(len(model_tool_events(seg)))}


def read_job(path: Path) -> list[str]:
    path = Path(path)
    if not path.is_file():
        raise NnikError("G-code file not found", str(path))
    return split_lines(path.read_bytes())


def python_model(outdir: Path, lines: list[str], cfg: MachineConfig, source: str):
    """(plan, segments, events) of the firmware's logic; the first bad line -> NnikError."""
    plan = interpret(lines, cfg)
    for reply in plan.replies:
        if reply != "ok":
            raise NnikError(reply.removeprefix("error: "), source)
    seg = plan_steps(plan, cfg, ik_oracle(outdir))
    return plan, seg, model_events(seg)


def chip_run(outdir: Path, lines: list[str], cfg: MachineConfig, seconds: float, workdir: Path) -> dict:
    """Export the library, build both sketches, run the self-test and the job on simavr."""
    from nnik.firmware.arduino import export_arduino
    from nnik.firmware.gcode import chip
    from nnik.targets.toolchain import TargetError

    lib = export_arduino(outdir, workdir / "library", cfg)
    name = lib["name"]
    try:
        selftest = chip.build_sketch(Path(lib["dir"]), f"{name}_selftest", workdir / "build")
        st = chip.run_firmware(selftest, [], workdir / "build", 5.0)
        fw = chip.build_sketch(Path(lib["dir"]), f"{name}_gcode", workdir / "build", cfg.defines())
        run = chip.run_firmware(fw, lines, workdir / "build", 2.0 + 1.5 * seconds)
    except TargetError as exc:
        raise NnikError(f"avr: {exc}") from None
    st_line = next((t for _, t in st.replies if t.startswith(("PASS", "FAIL"))), "no answer")
    return {"selftest": st_line, "selftest_pass": st_line.startswith("PASS"),
            "flash_bytes": fw.flash_bytes, "ram_bytes": fw.ram_bytes, "state": run.state,
            "replies": [t for _, t in run.replies if not t.startswith("nnik ")], "run": run,
            "events": chip_events(run.steps, run.marks, CLOCK_HZ // cfg.tick_hz),
            "tool_events": chip_tool_events(run.tool, run.marks, CLOCK_HZ // cfg.tick_hz),
            "segments_started": int(len(run.marks)), "end_cycle": run.end_cycle, **motion_times(run)}


def motion_times(run) -> dict:
    """When the chip's motion ended (its last tick: the machine fell idle after the whole job) and
    how long it ran from the first segment's first tick, in seconds of simulated time (None: no
    motion). Without stalls, motion_s is the model's seconds less one tick."""
    if not run.idle_cycle:
        return {"end_s": None, "motion_s": None}
    first = int(run.marks[0]) if len(run.marks) else run.idle_cycle
    return {"end_s": run.idle_cycle / CLOCK_HZ, "motion_s": (run.idle_cycle - first) / CLOCK_HZ}


def write_step_counts(path: Path, steps: np.ndarray, start: np.ndarray) -> Path:
    """Each motor's count over time as the chip's pins show it: cycle, motor, dir, count after."""
    counts = np.zeros((len(steps), 2), np.int64)
    sign = np.where(steps[:, 2] == 1, 1, -1)
    for m in range(2):
        sel = steps[:, 1] == m
        counts[sel, m] = start[m] + np.cumsum(sign[sel])
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = [f"{c},{m},{d},{counts[i, m]}" for i, (c, m, d) in enumerate(steps.tolist())]
    path.write_text("cycle,motor,dir,count\n" + "".join(r + "\n" for r in rows))
    return path


def run_job(outdir: Path, job_path: Path, seg_um: int | None = None, use_chip: bool | None = None) -> dict:
    """Run a job; use_chip None: on the simulated chip when the toolchain is there."""
    from nnik.firmware.config import default_machine
    from nnik.firmware.gcode import chip

    outdir, job_path = Path(outdir), Path(job_path)
    scn = load_scenario_of(outdir)
    cfg = default_machine(scn)
    if seg_um is not None:
        from dataclasses import replace

        try:
            cfg = replace(cfg, seg_um=seg_um)
        except ValueError as exc:
            raise NnikError(str(exc), None, "--seg-um") from None
    lines = read_job(job_path)
    cfg = job_machine(lines, cfg, str(job_path))
    # a long job shows its stage on a terminal (nothing in a log: nnik.progress)
    stages = bar(total=3, desc=f"job {job_path.name}", unit="stage", leave=False)
    stages.set_postfix_str("Python model of the firmware")
    plan, seg, events = python_model(outdir, lines, cfg, str(job_path))
    stages.update(1)
    res = {"scenario": scn.name, "job": job_path.name, "unit": scn.unit,
           "machine": {"origin_um": list(cfg.origin_um), "seg_um": cfg.seg_um, "tick_hz": cfg.tick_hz,
                       "tool": cfg.tool, "tool_defines": cfg.defines()},
           "tool": tool_report(seg, cfg), **contour_report(scn, cfg, plan, seg, events)}
    plot = res.pop("plot")
    why = chip.tool_missing_reason()
    if use_chip is False or (use_chip is None and why):
        res["chip"] = {"not_run": "not asked" if use_chip is False else why}
    else:
        if why:
            raise NnikError(f"avr: {why}")
        stages.set_postfix_str(f"simulated Uno ({res['seconds']:.1f} s of motion)")
        c = chip_run(outdir, lines, cfg, res["seconds"], outdir / JOB_DIR / "work" / job_path.stem)
        ev = c.pop("events")
        tev, want_tev = c.pop("tool_events"), model_tool_events(seg)
        run = c.pop("run")
        c["steps_csv"] = str(write_step_counts(outdir / JOB_DIR / f"{job_path.stem}_chip_steps.csv", run.steps, seg.steps[0]))
        same = (c["segments_started"] == res["segments"] and ev.shape == events.shape
                and bool((ev == events).all()))
        busy = (run.busy[:, 1] - run.busy[:, 0]).astype(np.float64)
        c.update({"steps": int(len(ev)), "steps_equal": same, "replies_equal": c["replies"] == plan.replies,
                  "tool_changes": int(len(tev)),
                  "tool_equal": tev.shape == want_tev.shape and bool((tev == want_tev).all())})
        if len(busy) and res["segments"]:
            # the sketch's busy pin is high while it parses, segments and runs the IK (interrupts
            # that fall inside included), low while it waits: busy cycles per segment, amortised,
            # and the longest stretch between two waits (one segment, with its line's parsing)
            mean = float(busy.sum()) / res["segments"]
            c["cycles_per_segment"] = {"mean": mean, "max": int(busy.max()), "windows": int(len(busy))}
            c["segment_rate_hz"] = {"mean": CPU_SHARE * CLOCK_HZ / mean}
        res["chip"] = c
    stages.update(1)
    stages.set_postfix_str("plot")
    out = outdir / JOB_DIR
    out.mkdir(parents=True, exist_ok=True)
    title = (f"{scn.name}: {job_path.name}, {res['segments']} segments of <= {cfg.seg_um} µm; contour error max "
             f"{res['contour_um']['max']:.1f} µm, RMS {res['contour_um']['rms']:.1f} µm")
    res["png"] = str(job_png(out / f"{job_path.stem}.png", title, plan, cfg, plot, seg))
    (out / f"{job_path.stem}.json").write_text(json.dumps(res, indent=2) + "\n")
    stages.update(1)
    stages.close()
    return res
