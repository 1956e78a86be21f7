"""The G-code firmware's motion logic in Python, bit for bit with codegen/arduino/src/nnik_gcode.c.

Lines become segment ends (program micrometres); the IK runs on all ends at once (it does not
feed back into the geometry); then each segment's steps and duration in ticks follow.
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
    first_seg: int  # index of its first segment
    n_seg: int
    center: tuple[int, int] | None = None
    radius: int = 0
    ccw: bool = True
    rapid: bool = False


@dataclass
class Plan:
    """Segment ends of a whole job, before the IK."""

    ends: list[tuple[int, int]] = field(default_factory=list)  # program um
    chord: list[int] = field(default_factory=list)  # floor length of each segment, um
    feed: list[int] = field(default_factory=list)  # um/min used for its ticks
    dwell: list[int] = field(default_factory=list)  # G4 or a tool change: its ticks (no steps); 0: a move
    tool: list[int] = field(default_factory=list)  # the tool word of each segment
    moves: list[Move] = field(default_factory=list)
    replies: list[str] = field(default_factory=list)  # "ok" or "error: line N: ..."


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

    # ---- segments ------------------------------------------------------------------------
    def _seg_to(self, x: int, y: int, feed: int) -> None:
        dx, dy = x - self.pos[0], y - self.pos[1]
        self.plan.ends.append((x + self.off[0], y + self.off[1]))
        self.plan.chord.append(isqrt(dx * dx + dy * dy))
        self.plan.feed.append(feed)
        self.plan.dwell.append(0)
        self.plan.tool.append(self.tool)
        self.last_tool = self.tool
        self.pos = (x, y)

    def _rest(self, ticks: int, tool: int) -> None:
        """A segment without steps (a dwell, a tool change) with a fixed tool word."""
        self.plan.ends.append((self.pos[0] + self.off[0], self.pos[1] + self.off[1]))
        self.plan.chord.append(0)
        self.plan.feed.append(self.feed)
        self.plan.dwell.append(ticks)
        self.plan.tool.append(tool)
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
        x0, y0 = self.pos
        dx, dy = x - x0, y - y0
        if dx == 0 and dy == 0:
            return
        length = isqrt(dx * dx + dy * dy)
        n = max(1, (length + self.cfg.seg_um - 1) // self.cfg.seg_um)
        for k in range(1, n + 1):
            self._seg_to(x0 + (dx * k) // n, y0 + (dy * k) // n, feed)

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
    """The firmware's output for a job: per segment, the steps and ticks it hands the stepper."""

    ends_um: np.ndarray  # (S, 2) program um
    steps: np.ndarray  # (S + 1, 2) actuator command at the start and after each segment
    delta: np.ndarray  # (S, 2)
    ticks: np.ndarray  # (S,)
    clamped: np.ndarray  # (S,) 1 where the IK clamped the end to its domain
    duty: np.ndarray | None = None  # (S,) the tool's duty (OCR2A, 0..255) during each segment
    chord: np.ndarray | None = None  # (S,) floor length of each segment, um


def plan_steps(plan: Plan, cfg: MachineConfig, ik) -> Segments:
    """Steps and ticks of every segment: ik(in_um (N, 2) int64) -> (out (N, 2), flags (N,))."""
    origin = np.asarray(cfg.origin_um, dtype=np.int64)
    ends = np.asarray(plan.ends, dtype=np.int64).reshape(-1, 2)
    out, flags = ik(np.concatenate([origin[None, :], ends + origin]))
    out = np.asarray(out, dtype=np.int64)
    delta = np.diff(out, axis=0)
    chord = np.asarray(plan.chord, dtype=np.int64)
    feed = np.asarray(plan.feed, dtype=np.int64)
    ticks = (chord * 60 * cfg.tick_hz + feed - 1) // feed
    tt = ticks
    ticks = np.maximum.reduce([ticks, np.abs(delta[:, 0]), np.abs(delta[:, 1]), np.ones_like(ticks)])
    dwell = np.asarray(plan.dwell, dtype=np.int64)
    ticks = np.where(dwell > 0, dwell, ticks)
    tool = np.asarray(plan.tool, dtype=np.int64)
    base = tool & 0xFF
    duty = np.where(tool & TOOL_SCALED, base * tt // ticks, base)  # M4: duty * speed / feed
    return Segments(ends, out, delta, ticks, np.asarray(flags, dtype=np.int64)[1:], duty, chord)


def interpret(lines: list[str], cfg: MachineConfig) -> Plan:
    """Run every line (errors are replies, as on the chip)."""
    it = Interpreter(cfg)
    for text in lines:
        it.line(text)
    return it.plan
