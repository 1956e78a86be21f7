"""The G-code firmware's motion logic in Python, bit for bit with codegen/arduino/src/nnik_gcode.c.

The interpreter turns lines into planner operations: a block per line or arc chord (machine
micrometres less the work origin), a flush (M400, M2, M30 and the end of the job) and rests
(G4, a tool change without motion: the planner first runs out to rest). sampler.run_ops plays
them through the planner, the fixed-rate sampler and the shaper as the chip does; the IK then
runs on all shaped samples at once (it does not feed back into the motion), and each sample
becomes a stepper segment of tick_hz / sample_hz ticks (more if a motor needs more steps: an
overspeed), each rest a segment without steps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import isqrt

import numpy as np

from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.interpreter import Interpreter
from nnik.firmware.gcode.program import Move, Plan  # noqa: F401  (the model's types, here since before)

@dataclass
class Segments:
    """The firmware's output for a job: per stepper segment (a sample or a rest), the steps and
    ticks it hands the stepper, and the sample stream behind them."""

    ends_um: np.ndarray  # (S, 2) the shaped point after each segment, um (machine less the origin)
    steps: np.ndarray  # (S + 1, 2) actuator command at the start and after each segment
    delta: np.ndarray  # (S, 2)
    ticks: np.ndarray  # (S,)
    clamped: np.ndarray  # (S,) 1 where the IK clamped the point to its domain
    duty: np.ndarray | None = None  # (S,) the tool's duty (OCR2A, 0..255) during each segment
    chord: np.ndarray | None = None  # (S,) floor length of each segment's shaped motion, um
    kind: np.ndarray | None = None  # (S,) 0: a sample, 1: a rest (G4, tool change)
    planned_um: np.ndarray | None = None  # (S, 2) the planner's point before the shaper
    speed_q16: np.ndarray | None = None  # (S,) planned speed, Q16 um/sample (0 at rest)
    move: np.ndarray | None = None  # (S,) the move of each segment (rests: the move before)
    sample_hz: int = 1000
    block: np.ndarray | None = None  # (S,) the push index of each sample's block (-1: a rest or the shaper's tail)

    @property
    def overspeed(self) -> int:
        """Samples whose steps needed more ticks than a sample has."""
        return int(((self.kind == 0) & (self.ticks > self.ticks_per_sample)).sum())

    @property
    def ticks_per_sample(self) -> int:
        return int(self.ticks[self.kind == 0].min()) if (self.kind == 0).any() else 0

    @property
    def speed_um_s(self) -> np.ndarray:
        return self.speed_q16 * self.sample_hz / 65536.0


def isqrt_rows(d: np.ndarray) -> np.ndarray:
    """floor(sqrt(x^2 + y^2)) of each row, exactly: in float64 with a correction while the squares
    are below 2^52 (samples move a few hundred um), else integer by integer."""
    if not len(d):
        return np.zeros(0, np.int64)
    if np.abs(d).max() >= 1 << 25:
        return np.array([isqrt(int(a * a + b * b)) for a, b in d.tolist()], dtype=np.int64)
    x = d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]
    r = np.floor(np.sqrt(x.astype(np.float64))).astype(np.int64)
    r -= (r * r > x).astype(np.int64)
    r += ((r + 1) * (r + 1) <= x).astype(np.int64)
    return r


def _move_of_blocks(plan: Plan) -> np.ndarray:
    idx = np.full(len(plan.ends), -1, np.int64)
    for m, mv in enumerate(plan.moves):
        idx[mv.first_seg:mv.first_seg + mv.n_seg] = m
    return idx


MAX_SEGMENT_STEPS = 65535  # the stepper interrupt's 16-bit DDA (gcode.ino.j2)


def plan_steps(plan: Plan, cfg: MachineConfig, ik) -> Segments:
    """Steps and ticks of every segment: ik(in_um (N, 2) int64) -> (out (N, 2), flags (N,))."""
    from nnik.firmware.gcode.planner import duty_of
    from nnik.firmware.gcode.sampler import run_ops

    st = run_ops(plan.ops, cfg)
    origin = np.asarray(cfg.origin_um, dtype=np.int64)
    kind = np.asarray(st.kind, dtype=np.int64)
    shaped = np.asarray(st.shaped, dtype=np.int64).reshape(-1, 2)
    samp = kind == 0
    out, flags = ik(np.concatenate([origin[None, :], shaped[samp] + origin]))
    out, flags = np.asarray(out, dtype=np.int64), np.asarray(flags, dtype=np.int64)
    k = np.cumsum(samp)  # samples up to and including each segment
    steps = np.concatenate([out[:1], out[k]])
    delta = np.diff(steps, axis=0)
    if len(delta) and int(np.abs(delta).max()) > MAX_SEGMENT_STEPS:
        raise NnikError(f"a sample moves a motor {int(np.abs(delta).max())} steps, more than the stepper's "
                        f"{MAX_SEGMENT_STEPS} a segment: the IK jumps")
    T = cfg.sample_ticks
    ticks = np.where(samp, np.maximum.reduce([np.full(len(kind), T), np.abs(delta[:, 0]), np.abs(delta[:, 1])]),
                     np.asarray(st.rest_ticks, dtype=np.int64))
    clamped = np.where(samp, flags[k], 0)
    prev = np.concatenate([np.zeros((1, 2), np.int64), shaped[:-1]])
    dd = shaped - prev
    chord = isqrt_rows(dd)
    bm = _move_of_blocks(plan)
    blk = np.asarray(st.block, dtype=np.int64)
    move = np.where(blk >= 0, bm[np.maximum(blk, 0)] if len(bm) else -1, -1)
    move = np.maximum(np.maximum.accumulate(move) if len(move) else move, 0)
    plan.seg_move = move
    return Segments(shaped, steps, delta, ticks, clamped, duty_of(st, cfg), chord, kind,
                    np.asarray(st.planned, dtype=np.int64).reshape(-1, 2), np.asarray(st.speed, dtype=np.int64),
                    move, cfg.sample_hz, blk)


def interpret(lines: list[str], cfg: MachineConfig) -> Plan:
    """Run every line (errors are replies, as on the chip)."""
    it = Interpreter(cfg)
    for text in lines:
        it.line(text)
    return it.plan
