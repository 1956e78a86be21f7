"""Stage 5 of a job, chip co-simulation: the library exported for this job's machine, both
sketches built with the Arduino AVR core (the self-test and NAME_gcode), and the job's lines sent
to the firmware on simavr.

build(model, ShapedJob.cfg, ...) -> BuiltChip (it may run while the Python model samples the
job); run(BuiltChip, ShapedJob, seconds) -> CoSimulated: the chip's replies, step and tool
events, its flash, RAM and stack, and when its motion ended.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode import chip
from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.firmware.gcode.simrun import ChipRun
from nnik.firmware.gcode.steps import chip_events, chip_tool_events
from nnik.firmware.model_dir import ModelDir
from nnik.job.shape import ShapedJob


@dataclass(frozen=True)
class BuiltChip:
    fw: chip.Firmware  # the NAME_gcode sketch, built
    selftest: str  # the self-test's PASS/FAIL line
    workdir: Path
    mcu: str


@dataclass
class CoSimulated:
    figures: dict  # self-test, flash, RAM, stack, state, replies, segments started, end and motion times
    run: ChipRun
    events: np.ndarray  # step events as the model's (nnik.firmware.gcode.steps.chip_events)
    tool_events: np.ndarray


def build(model: ModelDir, cfg: MachineConfig, workdir: Path, mcu: str = "atmega328p") -> BuiltChip:
    """Export the library, build both sketches (the core once per OUTDIR and MCU), run the
    self-test on simavr."""
    from nnik.firmware.arduino import export_arduino
    from nnik.targets.toolchain import TargetError

    lib = export_arduino(model.path, workdir / "library", cfg, model=model)
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
    return BuiltChip(fw, st_line, workdir, mcu)


def stream_figures(protocol: str, lines: list[str]) -> dict:
    """How the lines were streamed: grbl's character counting within the firmware's receive buffer
    (whitespace and comments out, as grbl senders send them), or send-response (one line in
    flight, as it is); the bytes sent."""
    sent = sum(len(ln) + 1 for ln in chip.sent_lines(lines, protocol))
    if protocol == "counting":
        return {"protocol": "character counting", "rx_buffer_bytes": chip.rx_buffer_bytes(),
                "lines": "whitespace and comments out", "bytes_sent": sent}
    return {"protocol": "send-response", "rx_buffer_bytes": None, "lines": "as they are", "bytes_sent": sent}


def run(built: BuiltChip, shaped: ShapedJob, seconds: float, progress=None,
        protocol: str = "counting") -> CoSimulated:
    """The job on the built firmware on simavr: replies, events, times (seconds: the job's
    planned time, the simulated-time bound's base; protocol: chip.PROTOCOLS, how the lines stream)."""
    from nnik.targets.toolchain import TargetError

    fw, cfg = built.fw, shaped.cfg
    try:
        run = chip.run_firmware(fw, shaped.lines, built.workdir / "build", 2.0 + 1.5 * seconds, progress=progress,
                                protocol=protocol)
    except TargetError as exc:
        raise NnikError(f"avr: {exc}") from None
    ram = chip.MCUS[built.mcu].ram_bytes
    if fw.ram_bytes + run.stack_bytes > ram:  # the stack ran into the static data: the run is not to be trusted
        raise NnikError(f"avr: the stack ({run.stack_bytes} B deep) ran into the static RAM ({fw.ram_bytes} B of "
                        f"{ram} B): a firmware defect, please report it")
    figures = {"selftest": built.selftest, "selftest_pass": built.selftest.startswith("PASS"),
               "flash_bytes": fw.flash_bytes, "ram_bytes": fw.ram_bytes, "stack_bytes": run.stack_bytes,
               "ram_free_bytes": ram - fw.ram_bytes - run.stack_bytes, "stream": stream_figures(protocol, shaped.lines),
               "state": run.state,
               "replies": [t for _, t in run.replies if not t.startswith(("nnik ", "Grbl ")) and t],
               "segments_started": int(len(run.marks)), "end_cycle": run.end_cycle, **motion_times(run)}
    return CoSimulated(figures, run, chip_events(run.steps, run.marks, CLOCK_HZ // cfg.tick_hz),
                       chip_tool_events(run.tool, run.marks, CLOCK_HZ // cfg.tick_hz))


def motion_times(run: ChipRun) -> dict:
    """When the chip's motion ended (its last tick: the machine fell idle after the whole job) and
    how long it ran from the first segment's first tick, in seconds of simulated time (None: no
    motion). Without stalls, motion_s is the model's seconds less one tick."""
    if not run.idle_cycle:
        return {"end_s": None, "motion_s": None}
    first = int(run.marks[0]) if len(run.marks) else run.idle_cycle
    return {"end_s": run.idle_cycle / CLOCK_HZ, "motion_s": (run.idle_cycle - first) / CLOCK_HZ}
