"""Stage 2 of a job, plan: the lines through the firmware's interpreter (its Python model, bit
for bit the chip's), into the planner's blocks, flushes and rests (nnik.firmware.gcode.program.Plan).

ParsedJob -> PlannedJob. The first line the firmware refuses -> NnikError FILE:LINE. `check`
stops here: grbl's $C, parse and plan only.
"""

from __future__ import annotations

from dataclasses import dataclass

from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.interpreter import Interpreter
from nnik.firmware.gcode.program import Plan
from nnik.job.parse import ParsedJob
from nnik.progress import bar

PROGRESS_LINES = 2000  # a job this long shows its lines going through the model (on a terminal)


@dataclass
class PlannedJob:
    parsed: ParsedJob
    plan: Plan  # the interpreter's operations for parsed.lines on parsed.cfg


def interpret(lines: list[str], cfg: MachineConfig, source: str, line_of: list[int] | None = None) -> Plan:
    """The interpreter's plan of the lines; the first refused line -> NnikError FILE:LINE
    (line_of: the file's line number of each line; None: the lines are counted)."""
    it = Interpreter(cfg)
    for k, raw in enumerate(bar(lines, desc="the firmware's model", unit="line", leave=False, position=1,
                                disable=len(lines) < PROGRESS_LINES)):
        if it.line(raw) not in ("ok", "$"):
            raise NnikError(f"{source}:{line_of[k] if line_of else k + 1}: {it.last_error}")
    return it.plan


def plan(parsed: ParsedJob) -> PlannedJob:
    return PlannedJob(parsed, interpret(parsed.lines, parsed.cfg, parsed.request.source, parsed.line_of))


def check(parsed: ParsedJob) -> dict:
    """`nnik job --check`: the file's summary and the planned motion (no IK, no chip, nothing
    written)."""
    from nnik.firmware.gcode.check import check_report

    req = parsed.request
    return {"scenario": req.scenario.name, "job": req.job.name, **parsed.summary,
            **check_report(parsed.lines, parsed.cfg)}
