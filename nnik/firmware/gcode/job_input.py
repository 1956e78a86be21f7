"""A G-code file made ready for the machine: read and checked, its flavour and tool rule said,
read once through the interpreter to find its extent, and fitted (or refused) against the travel.

Bad input gets one line naming the file and the line: an empty file, NUL bytes or binary data,
the first line the chip would refuse (grbl's error number and what is wrong), a job that leaves the
workspace (its extent, the travel, and the option that would fit it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

from nnik.errors import NnikError
from nnik.machine import ranges
from nnik.firmware.config import FEATURES, SCALE_ONE, TOOLS, MachineConfig
from nnik.firmware.gcode import fit as fitting
from nnik.firmware.gcode import step_directive
from nnik.firmware.gcode.flavour import FLAVOURS, choose_rule, detect, scan
from nnik.firmware.gcode.interpreter import Interpreter
from nnik.firmware.gcode.reader import split_lines

RAW_LINE_MAX = 1 << 20  # a line longer than this is no G-code


@dataclass(frozen=True)
class JobOptions:
    """What the command line says about a job (None: from the file and the scenario)."""

    flavour: str | None = None
    tool: str | None = None
    tool_rule: str | None = None
    tool_z_mm: float | None = None  # a pen-like tool is down at or below this Z
    fit: bool = False
    scale: float | None = None
    offset: tuple[float, float] | None = None


@dataclass
class Prepared:
    lines: list[bytes]  # what the chip is sent: every line but the $ lines (the sender's)
    line_of: list[int]  # the file's line number of each sent line
    cfg: MachineConfig
    summary: dict = field(default_factory=dict)


def read_job(path: Path) -> list[bytes]:
    """A job file's lines (LF, CRLF or CR); NnikError on what is no G-code."""
    path = Path(path)
    if path.is_dir():
        raise NnikError("a directory, not a G-code file", str(path))
    if not path.is_file():
        raise NnikError("G-code file not found", str(path))
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise NnikError(f"cannot read: {exc.strerror}", str(path)) from None
    if not data.strip():
        raise NnikError("empty file: no G-code in it", str(path))
    lines = split_lines(data)
    for k, ln in enumerate(lines, 1):
        if b"\0" in ln:
            raise NnikError(f"{path}:{k}: a NUL byte: binary data, not G-code")
        if len(ln) > RAW_LINE_MAX:
            raise NnikError(f"{path}:{k}: a line of {len(ln)} bytes: not G-code")
    ctrl = sum(1 for c in data[:65536] if c < 9 or 13 < c < 32)
    if ctrl > len(data[:65536]) // 100:
        raise NnikError(f"{path}: {ctrl} control bytes in its first 64 KiB: binary data, not G-code")
    return lines


def _check_options(opts: JobOptions) -> None:
    if opts.flavour is not None and opts.flavour not in FLAVOURS:
        raise NnikError(f"unknown flavour {opts.flavour!r}; choose one of {', '.join(FLAVOURS)}", None, "--flavour")
    if opts.tool is not None and opts.tool not in TOOLS:
        raise NnikError(f"unknown tool {opts.tool!r}; choose one of {', '.join(TOOLS)}", None, "--tool")
    for flag, v, problem in (("--scale", opts.scale, ranges.scale_problem), ("--tool-z", opts.tool_z_mm, ranges.tool_z_problem),
                             *(("--offset", o, ranges.offset_problem) for o in opts.offset or ())):
        if v is not None and (not math.isfinite(v) or problem(v)):
            raise NnikError(problem(v) or f"must be a finite number, got {v}", None, flag)
    if opts.fit and (opts.scale is not None or opts.offset is not None):
        raise NnikError("--fit chooses the scale and the offset itself: give --fit, or --scale/--offset", None, "--fit")


def _interpret(lines: list[bytes], cfg: MachineConfig, source: str) -> tuple[Interpreter, list[int], int]:
    """Every line once; the first refusal -> NnikError FILE:LINE. (interpreter, sent line numbers,
    $ lines)."""
    it = Interpreter(cfg)
    sent, dollars = [], 0
    for k, raw in enumerate(lines, 1):
        reply = it.line(raw)
        if reply == "$":
            dollars += 1
            it.plan.replies.pop()
            it.line_no -= 1
            continue
        sent.append(k)
        if reply != "ok":
            raise NnikError(f"{source}:{k}: {it.last_error}")
    return it, sent, dollars


def prepare(lines: list[bytes], cfg: MachineConfig, opts: JobOptions, source: str) -> Prepared:
    """The machine for this job (tool rule, flavour, frame, soft limits) and its summary."""
    _check_options(opts)
    step_directive.refuse(lines, source)  # a closed-loop job rewrites its steps before it comes here
    facts = scan(lines)
    flavour, evidence = (opts.flavour, "--flavour") if opts.flavour else detect(facts)
    if opts.tool:
        try:
            cfg = replace(cfg, tool=opts.tool, rule="")
        except ValueError as exc:
            raise NnikError(str(exc), None, "--tool") from None
    if opts.tool_z_mm is not None:
        cfg = replace(cfg, pen_z_um=int(round(opts.tool_z_mm * 1000)))
    rule, why = (opts.tool_rule, "--tool-rule") if opts.tool_rule else choose_rule(cfg.tool, flavour, facts)
    bounds = cfg.bounds_um
    try:
        first = replace(cfg, rule=rule, marlin=flavour == "marlin", bounds_um=None, scale_q16=SCALE_ONE, shift_um=(0, 0),
                        features=FEATURES)
    except ValueError as exc:
        raise NnikError(str(exc), None, "--tool-rule" if opts.tool_rule else "--tool") from None
    it, sent, dollars = _interpret(lines, first, source)
    ends = list(it.plan.ends)
    ext = fitting.extent(ends)
    unit_um = 25400 if facts.inch_first else 1000
    frame = fitting.Frame()
    if opts.fit and ext is not None and bounds is not None:
        frame = fitting.fit_frame(ext, bounds)
        while not fitting.inside([frame.apply(p) for p in ends], bounds) and frame.scale_q16 > 1:
            frame = replace(frame, scale_q16=frame.scale_q16 * 999 // 1000)
    elif opts.scale is not None or opts.offset is not None:
        frame = fitting.user_frame(opts.scale, opts.offset, unit_um)
    if bounds is not None and ext is not None and not fitting.inside([frame.apply(p) for p in ends], bounds):
        moved = fitting.extent([frame.apply(p) for p in ends])
        raise NnikError(f"{source}: {fitting.refusal(moved, bounds)}")
    # the chip's build carries the options this file uses, no more (each one's flash: docs/firmware.md)
    final = replace(first, scale_q16=frame.scale_q16, shift_um=frame.shift_um, bounds_um=bounds,
                    features=frozenset(it.features_used))
    z = it.z_seen or [0, 0]
    summary = {
        "flavour": flavour, "flavour_evidence": evidence, "tool": final.tool, "tool_rule": rule, "tool_rule_why": why,
        "moves_tool_on": it.moves_on, "moves_tool_off": it.moves_off, "frame": frame.how,
        "scale": frame.scale_q16 / SCALE_ONE, "offset_mm": [v / 1000 for v in frame.shift_um],
        "extent_mm": None if ext is None else [[v / 1000 for v in ext[0]], [v / 1000 for v in ext[1]]],
        "noted": dict(sorted(it.notes.items())), "dollar_lines": dollars, "last_word_wins": it.last_wins,
        "z_range_mm": [min(z) / 1000, max(z) / 1000], "lines": len(lines), "lines_sent": len(sent),
        "build_options": sorted(it.features_used),
    }
    return Prepared([lines[k - 1] for k in sent], sent, final, summary)
