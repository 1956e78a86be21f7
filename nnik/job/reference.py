"""A closed-loop job's reference: the G-code through the open-loop machines' interpreter and
planner (nnik.firmware.gcode, the planner sampled at the servo tick: [motion] sample_hz = 1 /
tick_s), one reference point per tick in encoder counts.

JobRequest -> ParsedJob (parse.prepare's checks, the workspace and --fit as the open-loop job has
them) -> Reference. The differences from the open-loop machines, all of the xy_table's:
- the program origin is the corner where the table homes (X0 Y0), not the workspace's centre, and
  the job starts there at rest;
- `;@step X.. Y..` lines (nnik.firmware.gcode.step_directive) are raw reference steps: the
  planned motion before one comes to rest, then the reference jumps to the target at the next tick;
- a dwell (G4) holds the reference for its time, rounded up to whole ticks, to let the loop settle.
Millimetres become counts at counts_per_rev per lead, rounded to the nearest count.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode import step_directive
from nnik.firmware.gcode.interpreter import Interpreter
from nnik.firmware.gcode.job_input import prepare, read_job
from nnik.firmware.gcode.program import Plan
from nnik.firmware.gcode.reader import sendable
from nnik.firmware.gcode.sampler import run_arrays
from nnik.job.parse import JobRequest, ParsedJob, machine_for
from nnik.machine.domain import domain_um


@dataclass(frozen=True)
class Reference:
    counts: np.ndarray  # (N, 2) int64: the reference at each tick
    step_ticks: tuple[int, ...]  # the ticks at which a ;@step lands
    tick_s: float
    um_per_count: float

    @property
    def seconds(self) -> float:
        return len(self.counts) * self.tick_s

    @property
    def um(self) -> np.ndarray:
        """The reference in um: the middle of each reference count (count c reads over [c, c + 1))."""
        return (self.counts + 0.5) * self.um_per_count


def servo_machine(scn, seg_um: int | None) -> MachineConfig:
    """The planner's configuration for a closed-loop job: the scenario's [motion], sampled once a
    servo tick, with the origin at the homing corner and the workspace as the soft limits."""
    cfg = machine_for(scn, "none", seg_um)
    per_s = 1.0 / scn.servo.tick_s
    if abs(cfg.sample_hz - per_s) > 1e-6 * per_s:
        raise NnikError(f"[motion] sample_hz = {cfg.sample_hz} must be one sample per servo tick "
                        f"({per_s:g} for tick_s = {scn.servo.tick_s:g} s)", scn.source, "[motion] sample_hz")
    lo, hi = domain_um(scn.workspace)
    # speed_search False: the reference's sampler keeps the rule before the search and the brake credit
    return replace(cfg, origin_um=(0, 0), bounds_um=((int(lo[0]), int(lo[1])), (int(hi[0]), int(hi[1]))),
                   speed_search=False)


def parse_closed(req: JobRequest) -> tuple[ParsedJob, frozenset[int]]:
    """The job read and prepared as a closed-loop job (its ;@step lines read as G0 for the extent,
    the frame and the checks); and the file line numbers of its steps."""
    raw = read_job(req.job)
    steps = frozenset(k for k, ln in enumerate(raw, 1) if step_directive.is_step(ln))
    lines = [step_directive.as_move(ln, f"{req.source}:{k}") if k in steps else ln for k, ln in enumerate(raw, 1)]
    cfg = servo_machine(req.scenario, req.seg_um)
    prep = prepare(lines, cfg, req.opts, req.source)
    parsed = ParsedJob(req, "none", prep.cfg, [sendable(ln).decode("latin-1") for ln in prep.lines], prep.line_of,
                       prep.summary)
    return parsed, steps


def interpret(parsed: ParsedJob, steps: frozenset[int]) -> Plan:
    """The interpreter's plan with each step line's move turned into ("flush",), ("step", x, y)."""
    it = Interpreter(parsed.cfg)
    for k, raw in enumerate(parsed.lines):
        n0 = len(it.plan.ops)
        if it.line(raw) not in ("ok", "$"):
            raise NnikError(f"{parsed.request.source}:{parsed.line_of[k]}: {it.last_error}")
        if parsed.line_of[k] in steps:
            new = it.plan.ops[n0:]
            pushes = [op for op in new if op[0] == "push"]
            if pushes:
                it.plan.ops[n0:] = [op for op in new if op[0] != "push"] + [("flush",), ("step",) + pushes[-1][1:3]]
    return it.plan


def _chunk(ops: list[tuple], start: tuple[int, int], cfg: MachineConfig) -> tuple[list, tuple[int, int]]:
    """The planner's samples (um) of ops from rest at start, rests held for whole ticks; the end."""
    shifted = [("push", op[1] - start[0], op[2] - start[1], *op[3:]) if op[0] == "push" else op for op in ops]
    a = run_arrays(shifted, cfg)
    per = cfg.tick_hz // cfg.sample_hz
    reps = np.where(a.kind == 1, -(-a.rest_ticks // per), 1)
    pts = np.repeat(a.shaped, reps, axis=0) + np.asarray(start, dtype=np.int64)
    end = tuple(int(v) for v in pts[-1]) if len(pts) else start
    return [pts], end


def reference(parsed: ParsedJob, steps: frozenset[int]) -> Reference:
    plan = interpret(parsed, steps)
    cfg, scn = parsed.cfg, parsed.scenario
    servo = scn.servo
    pos = tuple(int(v) for v in cfg.shift_um)  # where the job starts: its X0 Y0 through the frame
    pieces = [np.asarray([pos], dtype=np.int64)]
    step_rows, ops = [], []
    for op in plan.ops + [("end",)]:
        if op[0] not in ("step", "end"):
            ops.append(op)
            continue
        got, pos = _chunk(ops, pos, cfg)
        pieces += got
        ops = []
        if op[0] == "step":
            step_rows.append(sum(len(p) for p in pieces))
            pos = (int(op[1]), int(op[2]))
            pieces.append(np.asarray([pos], dtype=np.int64))
    um = np.concatenate(pieces)
    if len(um) < 2:
        raise NnikError(f"{parsed.request.source}: no motion, dwell or step in the job: nothing for the loop to follow")
    counts = np.floor(um * (servo.counts_per_rev / (servo.lead_mm * 1000.0)) + 0.5).astype(np.int64)
    return Reference(counts, tuple(step_rows), servo.tick_s, servo.um_per_count)


def job_reference(req: JobRequest) -> tuple[ParsedJob, Reference]:
    """parse_closed then reference: the job's per-tick reference in counts."""
    parsed, steps = parse_closed(req)
    return parsed, reference(parsed, steps)
