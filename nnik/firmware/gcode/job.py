"""`nnik job`: a G-code job through the firmware's logic in Python and on the simulated Uno.

The Python model gives every step (segment, tick, motor, direction) and the contour error;
the chip (the library's NAME_gcode sketch built with the Arduino AVR core, on simavr) must emit
the same steps. Reported: the job's time (planned with acceleration), the peak step rate against
the one-step-per-tick limit (and the samples that had to be stretched beyond it), and on the
chip the sample loop's share of the CPU (the busy pin's high time over the motion's time), its
cycles per sample, flash and SRAM. Results: OUTDIR/job/<job>.json and <job>.png.
"""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from nnik.dynamics.shaper_figures import axis_figures
from nnik.dynamics.shapers import KINDS
from nnik.files.atomic_write import write_file_atomic
from nnik.files.outdir import JOB_DIR
from nnik.progress import bar
from nnik.errors import NnikError
from nnik.firmware.gcode.contour import contour_report
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.interpreter import Interpreter
from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
from nnik.firmware.gcode.motion import plan_steps
from nnik.firmware.gcode.reader import sendable
from nnik.firmware.ik_oracle import ik_oracle, load_scenario_of
from nnik.firmware.gcode.plot import job_png
from nnik.firmware.gcode.tool_sync import summary, switches
from nnik.firmware.gcode.steps import chip_events, chip_tool_events, model_events, model_tool_events

CLOCK_HZ = 16_000_000
SHAPER_CHOICES = ("none",) + KINDS + ("auto",)


def tool_report(seg, cfg: MachineConfig) -> dict:
    """Tool-on (laser on, pen down) and travel length and the tool's on-time, from the segments."""
    on = seg.duty != cfg.tool_off_duty
    step = np.hypot(*np.diff(np.vstack([[0, 0], seg.ends_um]), axis=0).T)  # each segment's shaped motion, um
    return {"kind": cfg.tool, "on_mm": float(step[on].sum() / 1000.0),
            "travel_mm": float(step[~on].sum() / 1000.0), "on_s": float(seg.ticks[on].sum() / cfg.tick_hz),
            "changes": int(len(model_tool_events(seg)))}


PROGRESS_LINES = 2000  # a job this long shows its lines going through the model (on a terminal)
SLOW_JOB_S = 60.0  # a job with more motion than this, at an average speed far below the max feed, is said
SLOW_FRACTION = 0.01  # "far below": under 1 % of the max feed on average (an F1 typo: F1 is 1/3000 of 3000)


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


def python_model(outdir: Path, lines: list, cfg: MachineConfig, source: str, line_of: list[int] | None = None):
    """(plan, segments, events) of the firmware's logic; the first refused line -> NnikError
    FILE:LINE (line_of: the file's line number of each line)."""
    it = Interpreter(cfg)
    for k, raw in enumerate(bar(lines, desc="the firmware's model", unit="line", leave=False, position=1,
                                disable=len(lines) < PROGRESS_LINES)):
        if it.line(raw) not in ("ok", "$"):
            raise NnikError(f"{source}:{line_of[k] if line_of else k + 1}: {it.last_error}")
    seg = plan_steps(it.plan, cfg, ik_oracle(outdir))
    return it.plan, seg, model_events(seg)


def chip_build(outdir: Path, cfg: MachineConfig, workdir: Path, mcu: str = "atmega328p") -> dict:
    """Export the library, build both sketches (the core once per OUTDIR and MCU), run the
    self-test on simavr."""
    from nnik.firmware.arduino import export_arduino
    from nnik.firmware.gcode import chip
    from nnik.targets.toolchain import TargetError

    lib = export_arduino(outdir, workdir / "library", cfg)
    name = lib["name"]
    core = workdir.parent / "core"
    try:
        selftest = chip.build_sketch(Path(lib["dir"]), f"{name}_selftest", workdir / "build", mcu=mcu, core_dir=core)
        st = chip.run_firmware(selftest, [], workdir / "build", 5.0)
        fw = chip.build_sketch(Path(lib["dir"]), f"{name}_gcode", workdir / "build", chip.file_run_defines(cfg),
                               mcu=mcu, core_dir=core)
    except TargetError as exc:
        hint = ""
        if "does not fit" in str(exc) or "ld returned" in str(exc):
            opts = ", ".join(sorted(cfg.features)) or "none"
            hint = (f"; this job's build carries the options {opts} (docs/gcode.md): "
                    + ("run it with --mcu atmega2560, which carries everything" if mcu != "atmega2560" else "too big"))
        raise NnikError(f"avr: {exc}{hint}") from None
    st_line = next((t for _, t in st.replies if t.startswith(("PASS", "FAIL"))), "no answer")
    return {"fw": fw, "selftest": st_line, "workdir": workdir, "mcu": mcu}


def chip_job(built: dict, lines: list[str], cfg: MachineConfig, seconds: float, progress=None) -> dict:
    """The job on the built firmware (chip_build) on simavr: replies, events, times."""
    from nnik.firmware.gcode import chip
    from nnik.targets.toolchain import TargetError

    fw = built["fw"]
    try:
        run = chip.run_firmware(fw, lines, built["workdir"] / "build", 2.0 + 1.5 * seconds, progress=progress)
    except TargetError as exc:
        raise NnikError(f"avr: {exc}") from None
    ram = chip.MCUS[built.get("mcu", chip.MCU)].ram_bytes
    if fw.ram_bytes + run.stack_bytes > ram:  # the stack ran into the static data: the run is not to be trusted
        raise NnikError(f"avr: the stack ({run.stack_bytes} B deep) ran into the static RAM ({fw.ram_bytes} B of "
                        f"{ram} B): a firmware defect, please report it")
    return {"selftest": built["selftest"], "selftest_pass": built["selftest"].startswith("PASS"),
            "flash_bytes": fw.flash_bytes, "ram_bytes": fw.ram_bytes, "stack_bytes": run.stack_bytes,
            "ram_free_bytes": ram - fw.ram_bytes - run.stack_bytes, "state": run.state,
            "replies": [t for _, t in run.replies if not t.startswith(("nnik ", "Grbl ")) and t], "run": run,
            "events": chip_events(run.steps, run.marks, CLOCK_HZ // cfg.tick_hz),
            "tool_events": chip_tool_events(run.tool, run.marks, CLOCK_HZ // cfg.tick_hz),
            "segments_started": int(len(run.marks)), "end_cycle": run.end_cycle, **motion_times(run)}


def chip_run(outdir: Path, lines: list[str], cfg: MachineConfig, seconds: float, workdir: Path,
             mcu: str = "atmega328p", progress=None) -> dict:
    """Export the library, build both sketches, run the self-test and the job on simavr."""
    return chip_job(chip_build(outdir, cfg, workdir, mcu), lines, cfg, seconds, progress)


def cpu_report(run, busy: np.ndarray, samples: int) -> dict:
    """The sample loop's share of the CPU: the busy pin (high while the sketch parses, plans,
    samples, shapes, runs the IK and queues; low while it waits for queue room or input) over the
    motion's time, from the first segment to the machine's last tick; and busy cycles per sample."""
    first = int(run.marks[0]) if len(run.marks) else 0
    end = run.idle_cycle or run.end_cycle
    lo, hi = np.maximum(run.busy[:, 0], first), np.minimum(run.busy[:, 1], end)
    inside = float(np.maximum(hi - lo, 0).sum())
    out = {"cycles_per_sample": {"mean": float(busy.sum()) / max(samples, 1), "max": int(busy.max()),
                                 "windows": int(len(busy))}}
    if end > first:
        out["cpu_sample_loop"] = inside / (end - first)
    return out


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
            "shaper_ram_bytes": cfg.shaper_ram_bytes, "plan_blocks": cfg.plan_blocks,
            "shaper_figures": axis_figures(cfg.shaper_design if cfg.shaper != "none" else (), dyn)}


def machine_for(scn, shaper: str | None, seg_um: int | None) -> MachineConfig:
    """default_machine(scn) with the command line's --shaper and --seg-um; bad values: one line."""
    from dataclasses import replace

    from nnik.firmware.config import default_machine

    try:
        cfg = default_machine(scn, shaper)
    except ValueError as exc:
        raise NnikError(str(exc), None, "--shaper" if shaper else "[motion]") from None
    if seg_um is not None:
        try:
            cfg = replace(cfg, seg_um=seg_um)
        except ValueError as exc:
            raise NnikError(str(exc), None, "--seg-um") from None
    return cfg


def run_job(outdir: Path, job_path: Path, seg_um: int | None = None, use_chip: bool | None = None,
            shaper: str | None = None, precompensate: bool = False, opts: JobOptions | None = None,
            check: bool = False, mcu: str = "atmega328p", scenario=None, warn=None) -> dict:
    """Run a job; use_chip None: on the simulated chip when the toolchain is there (mcu: the Uno's
    atmega328p or the Mega's atmega2560; the sketches are built while the Python model runs, and
    the job runs on simavr while the plot is drawn); shaper:
    none|zv|mzv|zvd|ei|auto overrides the scenario's [motion] shaper; precompensate: run the
    job rewritten offline for the belts (nnik.firmware.gcode.compensation); opts: flavour, tool,
    tool rule and the job's frame (--fit, --scale, --offset); check: parse and plan only (grbl's
    $C), no IK, no chip, nothing written.  With a [dynamics] table every method is compared on
    the tip and the chosen one goes to the chip.  scenario: the machine's [motion], [dynamics] and
    [tool] (default: the model's, as it was trained; `nnik job SCENARIO.toml` gives the TOML's).
    warn: called at once with each warning line (a job whose motion is long for its length)."""
    from nnik.firmware.gcode import chip

    outdir, job_path = Path(outdir), Path(job_path)
    scn = scenario if scenario is not None else load_scenario_of(outdir)
    if shaper is not None and shaper not in SHAPER_CHOICES:
        raise NnikError(f"unknown shaper {shaper!r}; choose one of {', '.join(SHAPER_CHOICES)}", None, "--shaper")
    asked = "precompensated" if precompensate else (shaper or (scn.motion or {}).get("shaper", "none"))
    if asked != "none" and not scn.dynamics and not getattr(scn, "shaper", None):
        where = "--precompensate" if precompensate else "--shaper" if shaper else "[motion] shaper"
        raise NnikError(f"{'precompensation' if precompensate else 'shaper ' + repr(asked)} needs a [dynamics] table "
                        f"(f_hz, zeta) in {scn.source}", None, where)
    cfg = machine_for(scn, "none" if asked in ("auto", "precompensated") else asked, seg_um)
    prep = prepare(read_job(job_path), cfg, opts or JobOptions(), str(job_path))
    cfg, lines = prep.cfg, [sendable(ln).decode("latin-1") for ln in prep.lines]
    if check:
        from nnik.firmware.gcode.check import check_report

        return {"scenario": scn.name, "job": job_path.name, **prep.summary, **check_report(lines, cfg)}
    # a long job shows its stage on a terminal (nothing in a log: nnik.progress)
    stages = bar(total=4, desc=f"job {job_path.name}", unit="stage", leave=False)
    dyn_fig = None
    out = outdir / JOB_DIR
    out.mkdir(parents=True, exist_ok=True)
    if scn.dynamics:
        from nnik.firmware.gcode.compensation import job_dynamics

        stages.set_postfix_str("the belts: every compensation on the tip")
        try:
            cfg, lines, dyn_fig, _ = job_dynamics(scn, cfg, lines, ik_oracle(outdir), asked, precompensate,
                                                  str(job_path), out, job_path.stem)
        except ValueError as exc:
            raise NnikError(str(exc), str(job_path)) from None
    stages.update(1)
    why = chip.tool_missing_reason()
    use = not (use_chip is False or (use_chip is None and why))
    if use and why:
        raise NnikError(f"avr: {why}")
    pool = ThreadPoolExecutor(max_workers=1) if use else None  # the chip's builds beside the model
    try:
        work = outdir / JOB_DIR / "work" / job_path.stem
        built = pool.submit(chip_build, outdir, cfg, work, mcu) if use else None
        stages.set_postfix_str("Python model of the firmware")
        plan, seg, events = python_model(outdir, lines, cfg, str(job_path),
                                         prep.line_of if not precompensate else None)
        stages.update(1)
        res = {"scenario": scn.name, "job": job_path.name, "unit": scn.unit, "gcode": prep.summary,
               "machine": {"origin_um": list(cfg.origin_um), "seg_um": cfg.seg_um, "tick_hz": cfg.tick_hz,
                           "sample_hz": cfg.sample_hz, "shaper": cfg.shaper,
                           "tool": cfg.tool, "tool_defines": cfg.defines()},
               "tool": {**tool_report(seg, cfg), "switches": summary(switches(plan, seg, cfg))}, "motion": motion_report(seg, cfg, scn.dynamics),
               **contour_report(scn, cfg, plan, seg, events)}
        slow = slow_job_warning(res, cfg)
        if slow:
            res["warnings"] = [slow]
            if warn is not None:
                warn(slow)
        if res["clamped"]:
            raise NnikError(f"{res['clamped']} samples outside the IK's domain although the job fits the workspace: "
                            "a bug, please report it", str(job_path))
        plot = res.pop("plot")
        if dyn_fig is not None:
            chosen = dyn_fig["methods"][dyn_fig["chosen"]]
            res["dynamics"] = dyn_fig
            res["tip"] = {k: chosen[k] for k in ("contour_um", "dynamics_um", "ringing_um", "ringing_floor_um")}
        if not use:
            res["chip"] = {"not_run": "not asked" if use_chip is False else why}
        else:
            stages.set_postfix_str(f"simulated {'Mega' if mcu == 'atmega2560' else 'Uno'} "
                                   f"({res['seconds']:.1f} s of motion)")
            sim = bar(total=round(res["seconds"], 1), desc="chip", unit="s", leave=False, position=1,
                      bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s simulated [{elapsed}<{remaining}]")

            def progress(_answers: int, cycle: int) -> None:
                sim.update(max(0.0, min(cycle / CLOCK_HZ, res["seconds"]) - sim.n))

            ran = pool.submit(lambda: chip_job(built.result(), lines, cfg, res["seconds"], progress))
        stages.set_postfix_str("plot")
        title = (f"{scn.name}: {job_path.name}, {res['motion']['job_s']:.2f} s ({cfg.sample_hz} Hz samples, shaper "
                 f"{cfg.shaper}); contour error max "
                 f"{res['contour_um']['max']:.1f} µm, RMS {res['contour_um']['rms']:.1f} µm")
        res["png"] = str(job_png(out / f"{job_path.stem}.png", title, plan, cfg, plot, seg))
        stages.update(1)
        if use:
            c = ran.result()
            sim.close()
            res["chip"] = compare_chip(c, res, plan, seg, events, out, job_path.stem)
        stages.update(1)
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    res["png"] = res.pop("png")  # the key order of the JSON before the chip ran beside the plot
    write_file_atomic(out / f"{job_path.stem}.json", json.dumps(res, indent=2) + "\n")
    stages.close()
    return res


def compare_chip(c: dict, res: dict, plan, seg, events, out: Path, stem: str) -> dict:
    """The chip's run against the model: steps, replies, tool changes; the sample loop's CPU."""
    ev = c.pop("events")
    tev, want_tev = c.pop("tool_events"), model_tool_events(seg)
    run = c.pop("run")
    c["steps_csv"] = str(write_step_counts(out / f"{stem}_chip_steps.csv", run.steps, seg.steps[0]))
    same = (c["segments_started"] == res["segments"] and ev.shape == events.shape
            and bool((ev == events).all()))
    busy = (run.busy[:, 1] - run.busy[:, 0]).astype(np.float64)
    c.update({"steps": int(len(ev)), "steps_equal": same, "replies_equal": c["replies"] == plan.replies,
              "tool_changes": int(len(tev)),
              "tool_equal": tev.shape == want_tev.shape and bool((tev == want_tev).all())})
    if len(busy) and res["segments"]:
        c.update(cpu_report(run, busy, res["motion"]["samples"]))
    return c
