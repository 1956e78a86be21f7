"""The G-code firmware's motion logic in Python, bit for bit with codegen/arduino/src/nnik_gcode.c.

The interpreter turns lines into planner operations: a block per line or arc chord (machine
micrometres less the work origin), a flush (M400, M2, M30 and the end of the job) and rests
(G4, a tool change without motion: the planner first runs out to rest). planner.run_ops plays
them through the planner, the fixed-rate sampler and the shaper as the chip does; the IK then
runs on all shaped samples at once (it does not feed back into the motion), and each sample
becomes a stepper segment of tick_hz / sample_hz ticks (more if a motor needs more steps: an
overspeed), each rest a segment without steps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import isqrt

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.parse import GcodeLineError, parse_line

POS_LIMIT = 2**28 - 1  # um
TOOL_SCALED = 0x100  # a tool word: duty | TOOL_SCALED (M4: duty * the segment's speed / feed)
MIN_FEED = 1000  # um/min
ARC_STACK = 32


@dataclass(frozen=True)
class Move:
    """One programmed move: a line or an arc (centre, radius, direction), in program um."""

    line_no: int
    kind: str  # "line" | "arc"
    start: tuple[int, int]
    end: tuple[int, int]
    first_seg: int  # index of its first planner block (push)
    n_seg: int  # its blocks
    center: tuple[int, int] | None = None
    radius: int = 0
    ccw: bool = True
    rapid: bool = False


@dataclass
class Plan:
    """A whole job as planner operations, before the planner and the IK."""

    ends: list[tuple[int, int]] = field(default_factory=list)  # block ends, um (machine less the origin)
    feed: list[int] = field(default_factory=list)  # um/min of each block
    tool: list[int] = field(default_factory=list)  # the tool word of each block
    dwell: list[int] = field(default_factory=list)  # ticks of each rest (G4, or 1: a tool change)
    ops: list[tuple] = field(default_factory=list)  # ("push", x, y, feed, tool, i), ("flush",), ("rest", ticks, tool)
    moves: list[Move] = field(default_factory=list)
    replies: list[str] = field(default_factory=list)  # "ok" or "error: line N: ..."
    seg_move: np.ndarray | None = None  # set by plan_steps: the move of every stepper segment


def _floordiv(a: int, n: int) -> tuple[int, int]:
    return a // n, a % n


def _div_round(a: int, b: int) -> int:
    q = (2 * abs(a) + b) // (2 * b)
    return -q if a < 0 else q


def r_centre(x: int, y: int, rad: int, ccw: bool) -> tuple[int, int]:
    """The centre of an R-form arc as an offset (I, J) from its start, for the chord (x, y) and
    the radius rad (not zero; negative: the long way round), as r_centre() in nnik_gcode.c:
    (x, y) / 2 + sign * (-y, x) * s / (2 d), s = floor(sqrt(4 rad^2 - d^2)) (0 when the chord
    is longer than 2|rad| by at most the end tolerance), d = |(x, y)| taken as floor(d * 2^k) / 2^k
    with 2^29 <= d * 2^k < 2^30; the centre lies left of the chord for G3 and a positive R."""
    d2 = x * x + y * y
    if d2 == 0:
        raise GcodeLineError("R arc ends at its start")
    ra = abs(rad)
    s = 0
    if 4 * ra * ra < d2:
        if isqrt(d2) > 2 * ra + 5 + ra // 1000:
            raise GcodeLineError("arc chord longer than 2|R|")
    else:
        s = isqrt(4 * ra * ra - d2)
    k, d2s = 0, d2
    while d2s < 1 << 58:
        d2s <<= 2
        k += 1
    ds = isqrt(d2s)
    sign = 1 if ccw == (rad > 0) else -1
    return (_div_round(x * ds - sign * (y << k) * s, 2 * ds), _div_round(y * ds + sign * (x << k) * s, 2 * ds))


class Interpreter:
    """The state of nnik_gc_t without the IK: program position, modes, feed."""

    def __init__(self, cfg: MachineConfig):
        self.cfg = cfg
        self.pos = (0, 0)
        self.off = (0, 0)  # G92: machine position (less the work origin) = pos + off
        self.spindle, self.s, self.z = 0, 0, 0  # M3/M4/M5 (0: off), S in thousandths, Z um
        self.tool = self.last_tool = 0
        self.feed = cfg.feed_um_min
        self.motion = 0
        self.inch = False
        self.relative = False
        self.line_no = 0
        self.plan = Plan()

    # ---- blocks ---------------------------------------------------------------------------
    def _seg_to(self, x: int, y: int, feed: int) -> None:
        end = (x + self.off[0], y + self.off[1])
        self.plan.ops.append(("push", end[0], end[1], feed, self.tool, len(self.plan.ends)))
        self.plan.ends.append(end)
        self.plan.feed.append(feed)
        self.plan.tool.append(self.tool)
        self.last_tool = self.tool
        self.pos = (x, y)

    def _rest(self, ticks: int, tool: int) -> None:
        """A segment without steps (a dwell, a tool change) with a fixed tool word, once the
        planned motion is at rest."""
        self.plan.ops.append(("rest", ticks, tool))
        self.plan.dwell.append(ticks)
        self.tool = self.last_tool = tool

    def _dwell(self, ms: int) -> None:
        t = ms // 1000 * self.cfg.tick_hz + ms % 1000 * self.cfg.tick_hz // 1000
        if t:
            self._rest(t, self.idle_tool())

    def idle_tool(self) -> int:
        """The tool word at rest: laser off (grbl's laser mode); pen up or down by Z."""
        if self.cfg.tool == "laser":
            return 0
        return self.cfg.pen_duty(self.z <= self.cfg.pen_z_um)

    def move_tool(self, rapid: bool) -> int:
        """The tool word of a move: off for rapids and M5, S's duty for M3, scaled for M4."""
        if self.cfg.tool != "laser":
            return self.idle_tool()
        if rapid or not self.spindle:
            return 0
        full = self.cfg.s_max * 1000
        t = min(self.s, full) * 255 // full
        return t | TOOL_SCALED if self.spindle == 4 else t

    def _tool_state(self, w, z: int) -> None:
        if "S" in w.values:
            self.s = w.values["S"].to_um(False)
        if w.spindle is not None:
            self.spindle = 0 if w.spindle == 5 else w.spindle
        self.z = z

    def _move(self, motion: int, tgt, c=None, r: int = 0, feed: int = 0) -> None:
        """A line (motion 0/1) or an arc to tgt, recorded as a Move in the machine frame less
        the work origin (program position + the G92 offset)."""
        start, first = self.pos, len(self.plan.ends)
        if motion >= 2:
            self._arc_to(c, tuple(tgt), r, motion == 3, feed)
        else:
            self._line_to(tgt[0], tgt[1], feed)
        n = len(self.plan.ends) - first
        if n:
            o = self.off
            sh = lambda p: (p[0] + o[0], p[1] + o[1])  # noqa: E731
            self.plan.moves.append(Move(self.line_no, "arc" if motion >= 2 else "line", sh(start), sh(tgt), first, n,
                                        None if c is None else sh(c), r, motion == 3, motion == 0))

    def _line_to(self, x: int, y: int, feed: int) -> None:
        if (x, y) != self.pos:
            self._seg_to(x, y, feed)  # one block: the planner samples it

    def _arc_piece(self, c, cur, end, r, feed):
        seg2 = self.cfg.seg_um**2
        stack = [end]
        while stack:
            b = stack[-1]
            if (b[0] - cur[0]) ** 2 + (b[1] - cur[1]) ** 2 <= seg2 or len(stack) == ARC_STACK:
                cur = b
                stack.pop()
                self._seg_to(c[0] + cur[0], c[1] + cur[1], feed)
            else:
                mx, my = cur[0] + b[0], cur[1] + b[1]
                m = isqrt(mx * mx + my * my)
                stack.append((_div_round(mx * r, m), _div_round(my * r, m)))
        return cur

    def _arc_to(self, c, end, r, ccw, feed):
        cur = (self.pos[0] - c[0], self.pos[1] - c[1])
        e = (end[0] - c[0], end[1] - c[1])
        while True:
            cross = cur[0] * e[1] - cur[1] * e[0]
            dot = cur[0] * e[0] + cur[1] * e[1]
            if not ccw:
                cross = -cross
            if cross > 0 and dot >= 0:
                self._arc_piece(c, cur, e, r, feed)
                return
            nxt = (-cur[1], cur[0]) if ccw else (cur[1], -cur[0])
            self._arc_piece(c, cur, nxt, r, feed)
            cur = nxt

    # ---- lines -----------------------------------------------------------------------------
    def line(self, text: str) -> str:
        """Run one line; returns "ok" or the firmware's error reply (nothing moves then)."""
        self.line_no += 1
        try:
            self._line(text)
        except GcodeLineError as exc:
            reply = f"error: line {self.line_no}: {exc}"
        else:
            reply = "ok"
        self.plan.replies.append(reply)
        return reply

    def _line(self, text: str) -> None:
        w = parse_line(text, pen=self.cfg.tool != "laser")
        nm = w.nonmodal
        if nm and w.motion is not None:
            raise GcodeLineError(f"G{nm} with a motion command")
        v = w.values
        if "P" in v and nm != 4:
            raise GcodeLineError("P needs G4")
        if "S" in v and v["S"].neg:
            raise GcodeLineError("negative S")
        if "Z" in v and nm:
            raise GcodeLineError("Z needs G0 to G3")
        seg0 = len(self.plan.ends)
        inch = self.inch if w.inch is None else w.inch
        rel = self.relative if w.relative is None else w.relative
        motion = self.motion if w.motion is None else w.motion
        feed = self.feed
        if "F" in v:
            feed = v["F"].to_um(inch)
            if feed < MIN_FEED:
                raise GcodeLineError("feed below 1 mm/min")
        if ("I" in v or "J" in v) and (motion < 2 or nm):
            raise GcodeLineError("I/J need G2 or G3")
        if "R" in v and (motion < 2 or nm):
            raise GcodeLineError("R needs G2 or G3")
        tgt = list(self.pos)
        for k, axis in enumerate("XY"):
            if axis in v:
                val = v[axis].to_um(inch)
                tgt[k] = self.pos[k] + val if rel and nm != 92 else val
            if abs(tgt[k]) > POS_LIMIT:
                raise GcodeLineError("coordinate out of range")
        z = self.z
        if "Z" in v:
            z = z + v["Z"].to_um(inch) if rel else v["Z"].to_um(inch)
            if abs(z) > POS_LIMIT:
                raise GcodeLineError("coordinate out of range")
        if nm:
            self._nonmodal(w, nm, tgt, inch, rel, feed, z)
        else:
            self._motion(w, tgt, inch, rel, motion, feed, z)
        if w.end:  # M2/M30 end the program as grbl: G1, G90, M5
            self.motion, self.relative, self.spindle = 1, False, 0
        # a tool word that turns a laser off (M5, S0, M2/M30) or moves the pen, and no segment on
        # this line: the tool changes on the next tick, by a one-tick segment without steps, if the
        # last segment left it otherwise (a new power alone waits for the next cut)
        toolword = w.spindle is not None or "S" in v or "Z" in v or w.end
        if (toolword and len(self.plan.ends) == seg0 and self.last_tool != self.idle_tool()
                and (self.cfg.tool != "laser" or self.move_tool(False) == 0)):
            self._rest(1, self.idle_tool())
        if w.wait:  # M400, M2, M30: the planner runs out to rest
            self.plan.ops.append(("flush",))

    def _nonmodal(self, w, nm: int, tgt: list[int], inch: bool, rel: bool, feed: int, z: int) -> None:
        v = w.values
        xy = "X" in v or "Y" in v
        ms = v["P"].to_um(False) if "P" in v else -1
        if nm == 4 and (ms < 0 or xy):
            raise GcodeLineError("G4 needs P >= 0")
        if nm == 92:
            if not xy:
                raise GcodeLineError("G92 needs X or Y")
            off = tuple(self.off[k] + self.pos[k] - tgt[k] for k in range(2))
            if any(abs(o) > POS_LIMIT for o in off):
                raise GcodeLineError("coordinate out of range")
            self.off, self.pos = off, tuple(tgt)
        self.inch, self.relative, self.feed = inch, rel, feed
        self._tool_state(w, z)
        if nm == 4:
            self._dwell(ms)
        elif nm == 28:  # via X Y (if given), then home: where the motors started
            rapid = self.cfg.rapid_um_min
            self.tool = self.move_tool(True)
            self._move(0, tgt, feed=rapid)
            home = [-self.off[k] if ("XY"[k] in v or not xy) else tgt[k] for k in range(2)]
            self._move(0, home, feed=rapid)

    def _motion(self, w, tgt: list[int], inch: bool, rel: bool, motion: int, feed: int, z: int) -> None:
        v = w.values
        axes = any(a in v for a in "XYIJR")
        c, r = None, 0
        if axes and motion >= 2:
            if "R" in v:
                rad = v["R"].to_um(inch)
                if "I" in v or "J" in v:
                    raise GcodeLineError("arc with both R and I/J")
                if rad == 0:
                    raise GcodeLineError("arc radius is zero")
                off = r_centre(tgt[0] - self.pos[0], tgt[1] - self.pos[1], rad, motion == 3)
            elif "I" not in v and "J" not in v:
                raise GcodeLineError("arc needs I, J or R")
            else:
                off = (v["I"].to_um(inch) if "I" in v else 0, v["J"].to_um(inch) if "J" in v else 0)
            c = (self.pos[0] + off[0], self.pos[1] + off[1])
            if abs(c[0]) > POS_LIMIT or abs(c[1]) > POS_LIMIT:
                raise GcodeLineError("coordinate out of range")
            a = (self.pos[0] - c[0], self.pos[1] - c[1])
            e = (tgt[0] - c[0], tgt[1] - c[1])
            r = isqrt(a[0] ** 2 + a[1] ** 2)
            if r == 0:
                raise GcodeLineError("arc radius is zero")
            re = isqrt(e[0] ** 2 + e[1] ** 2)
            if re == 0 or abs(re - r) > 5 + r // 1000:
                raise GcodeLineError("arc end is off the circle")
        self.inch, self.relative, self.motion, self.feed = inch, rel, motion, feed
        self._tool_state(w, z)
        if axes:
            self.tool = self.move_tool(motion == 0)
            self._move(motion, tgt, c, r, self.cfg.rapid_um_min if motion == 0 else feed)


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


def _move_of_blocks(plan: Plan) -> np.ndarray:
    idx = np.full(len(plan.ends), -1, np.int64)
    for m, mv in enumerate(plan.moves):
        idx[mv.first_seg:mv.first_seg + mv.n_seg] = m
    return idx


def plan_steps(plan: Plan, cfg: MachineConfig, ik) -> Segments:
    """Steps and ticks of every segment: ik(in_um (N, 2) int64) -> (out (N, 2), flags (N,))."""
    from nnik.firmware.gcode.planner import duty_of, run_ops

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
    T = cfg.sample_ticks
    ticks = np.where(samp, np.maximum.reduce([np.full(len(kind), T), np.abs(delta[:, 0]), np.abs(delta[:, 1])]),
                     np.asarray(st.rest_ticks, dtype=np.int64))
    clamped = np.where(samp, flags[k], 0)
    prev = np.concatenate([np.zeros((1, 2), np.int64), shaped[:-1]])
    dd = shaped - prev
    chord = np.array([isqrt(int(a * a + b * b)) for a, b in dd.tolist()], dtype=np.int64)
    bm = _move_of_blocks(plan)
    blk = np.asarray(st.block, dtype=np.int64)
    move = np.where(blk >= 0, bm[np.maximum(blk, 0)] if len(bm) else -1, -1)
    move = np.maximum(np.maximum.accumulate(move) if len(move) else move, 0)
    plan.seg_move = move
    return Segments(shaped, steps, delta, ticks, clamped, duty_of(st), chord, kind,
                    np.asarray(st.planned, dtype=np.int64).reshape(-1, 2), np.asarray(st.speed, dtype=np.int64),
                    move, cfg.sample_hz)


def interpret(lines: list[str], cfg: MachineConfig) -> Plan:
    """Run every line (errors are replies, as on the chip)."""
    it = Interpreter(cfg)
    for text in lines:
        it.line(text)
    return it.plan
