"""The firmware's motion planner and fixed-rate sampler in Python, bit for bit with
codegen/arduino/src/nnik_plan.c and nnik_plan_sample.c (their header, nnik_plan.h, states every rule
and rounding; in short):

* units: um (machine frame less the work origin), speeds Q16 um/sample, accelerations Q16
  um/sample^2, unit vectors Q30; a block is a line or an arc chord (or, with
  MachineConfig.arc_blocks, a whole arc: nnik.firmware.gcode.planner_arc, not on the chip yet);
* lookahead: grbl 1.1's junction deviation (the junction vector's axis limit) at each junction,
  rounded downward, a backward pass for the exit speeds (braking by the least acceleration of the
  block and of the blocks a sample may start in and land in it from), the last queued block
  ending at rest;
  the sampler changes speed by at most the block's acceleration per sample (the forward pass is
  implicit) and passes a block end at most at its junction's limit, able to brake in the block it
  lands in, with the brake test's credit (MachineConfig.brake_alpha_q16, NNIK_PL_ALPHA)
  (nnik.bench.planner_oracle is the float grbl planner it is checked against);
* determinism: samples are taken only while the queue is full (until the head block is left
  behind) or flushed (until it is empty), so they depend on the block order alone.

``run_ops_reference`` (and nnik.firmware.gcode.sampler.run_ops, in bulk) plays the interpreter's operations (push, flush, rest) through the planner, the shaper
and the sample clock the way nnik_gcode.c does, and returns the stream of stepper segments before
the IK (one per sample, plus the rest segments).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import isqrt

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.planner_arc import Chords, arc_chords, arc_point
from nnik.firmware.gcode.tool_shaper import stream_duty

Q30 = 1 << 30
U32 = 0xFFFFFFFF
R_MAX = 0x7FFFFFFF


@dataclass
class Block:
    end: tuple[int, int]
    u: tuple[int, int]
    len: int
    vn: int
    acc: int
    tool: int
    index: int  # the push's index in the job (its move is the interpreter's)
    lfr: int = 0  # the length's fraction, Q16: the length is len + lfr / 65536 um (floor)
    jmax: int = 0
    exit: int = 0
    u_out: tuple[int, int] | None = None  # an arc block's last chord's u (planner_arc); None: u
    chords: Chords | None = None  # an arc block's chords (planner_arc); None: a line

    @property
    def l16(self) -> int:
        """The length, Q16 um."""
        return (self.len << 16) | self.lfr


DOT_MARGIN = 8  # nnik_plan.h NNIK_PL_DOT_MARGIN
REVERSAL = 1073  # NNIK_PL_REVERSAL


def _acc_axis(a: int, L: int, n: int) -> int:
    return min(a * L // n, U32)


def length_q(dx: int, dy: int) -> tuple[int, int, int]:
    """(Lq, Lc, f): Lq = floor(sqrt(n) 2^f) with n 4^f in [2^60, 2^62), Lc = ceil of the same."""
    m, f = dx * dx + dy * dy, 0
    while m < 1 << 60:
        m, f = m << 2, f + 1
    Lq = isqrt(m)
    return Lq, Lq + (Lq * Lq != m), f


def junction2(a: Block, b: Block, cfg: MachineConfig) -> int:
    """The square of the speed limit at the junction a -> b, Q16, before the feeds' cap (U32:
    straight on; nnik_plan.c junction2())."""
    au = a.u if a.u_out is None else a.u_out  # an arc leaves along its last chord
    dot = ((au[0] * b.u[0] + au[1] * b.u[1]) >> 30) - DOT_MARGIN
    if dot <= -Q30 + REVERSAL:
        return 0  # a reversal
    if dot >= Q30 - REVERSAL:
        return U32  # straight on: the feeds'
    sn = isqrt((Q30 + dot) << 1)  # sin(theta / 2), Q16
    w = [abs(b.u[i] - au[i]) for i in range(2)]
    hi, k = [c + 4 for c in w], 0
    while max(hi) >= 0x8000:  # to 15 bits, halving, rounded up
        hi, k = [(c + 1) >> 1 for c in hi], k + 1
    w2 = hi[0] ** 2 + hi[1] ** 2
    wl = max(isqrt(w2) - 13, 0)  # each hi_i <= the exact |w_i| 2^-k + 9
    aj = min(min(_acc_axis(acc, wl, c) for acc, c in zip(cfg.acc_q16, hi)), 0x7FFFFF)
    r = (sn * (0x10000 + sn) << 14) // w2  # 4 sin (1 + sin) / |w|^2, Q16: this 2^(32 - 2k)
    r = min(r << (32 - 2 * k), R_MAX) if k < 16 else r >> (2 * k - 32)
    return min(min(aj * cfg.junction_dev_um, U32) * r >> 16, U32)


def junction(a: Block, b: Block, cfg: MachineConfig) -> int:
    """The speed limit at the junction a -> b: floor(sqrt(j2 2^16)) of its square (nnik_plan.c junction())."""
    j2, lim = junction2(a, b, cfg), min(a.vn, b.vn)
    return lim if j2 == U32 else min(isqrt(j2 << 16), lim)


def brake_acc(q: list[Block], k: int) -> int:
    """The acceleration the backward pass brakes by over block k + 1 (nnik_plan.c brake_acc()): the
    least of its own and of every block before it that a sample may start in and land in it from
    (block k, and each q[m] while the blocks between are shorter than a sample of q[m] travels,
    at most max(vn, acc); the lengths between in whole um, against that >> 16))."""
    a, gap, m = min(q[k + 1].acc, q[k].acc), 0, k
    while m > 0:
        gap += q[m].len
        m -= 1
        if gap > max(q[m].vn, q[m].acc) >> 16:
            break
        a = min(a, q[m].acc)
    return a


def motor_caps(cfg: MachineConfig, dx: int, dy: int, Lq: int, Lc: int, f: int, vn: int, acc: int) -> tuple[int, int]:
    """(vn, acc) within the motor limits after the IK (nnik_plan.c motor_caps(); the rows:
    nnik.machine.motor_limits): per motor n = ceil((|cx dx + cy dy| + d Lc 2^-f) 2^f / 2^15),
    vn <= floor(V Lq / n), acc <= floor(A Lq / n); vn <= vc."""
    rows, vc = cfg.motor_q16
    for cx, cy, d, v, a in rows:
        n = (abs(cx * (dx << f) + cy * (dy << f)) + d * Lc + 0x7FFF) >> 15
        if n:
            vn = min(vn, _acc_axis(v, Lq, n)) if v else vn
            acc = min(acc, _acc_axis(a, Lq, n)) if a else acc
    return (min(vn, vc) if vc else vn), acc


class Planner:
    """nnik_plan_t: the queue, the head's progress and the speed."""

    def __init__(self, cfg: MachineConfig, p=(0, 0)):
        self.cfg = cfg
        self.n = cfg.lookahead
        self.q: list[Block] = []
        self.start = tuple(p)
        self.last = tuple(p)
        self.s = 0  # Q16 um along the head block
        self.v = 0
        self.acc = cfg.acc_q16
        self.alpha = cfg.brake_alpha_q16  # the brake test's credit (NNIK_PL_ALPHA)
        self.cross_jmax = cfg.brake_credit  # block ends passed at most at their junction's limit (else: exit)

    def full(self) -> bool:
        return len(self.q) == self.n

    def ready(self, flushing: bool) -> bool:
        return len(self.q) == self.n or (flushing and bool(self.q))

    def push(self, x: int, y: int, feed: int, tool: int, index: int) -> None:
        dx, dy = x - self.last[0], y - self.last[1]
        if not dx and not dy:
            return
        Lq, Lc, f = length_q(dx, dy)
        feed = min(feed, self.cfg.max_feed_um_min)
        vn = (feed << 16) // (60 * self.cfg.sample_hz)
        acc = U32
        for a, d in zip(self.acc, (dx, dy)):
            if d:
                acc = min(acc, _acc_axis(a, Lq, abs(d) << f))
        vn, acc = motor_caps(self.cfg, dx, dy, Lq, Lc, f, vn, acc) if self.cfg.motor_rows else (vn, acc)
        u = tuple((abs(d) << (30 + f)) // Lc * (-1 if d < 0 else 1) for d in (dx, dy))
        lfr = (Lq >> (f - 16) if f >= 16 else Lq << (16 - f)) & 0xFFFF
        self._queue(Block((x, y), u, Lq >> f, vn, acc, tool, index, lfr))

    def _queue(self, b: Block) -> None:
        """The block at the queue's end: its junction with the one before, the backward pass."""
        if self.q:
            self.q[-1].jmax = junction(self.q[-1], b, self.cfg)
        self.q.append(b)
        self.last = b.end
        self._backward()

    def vertex(self, u1: tuple[int, int], u2: tuple[int, int]) -> int:
        """The junction limit between two chords with unit vectors u1, u2 (planner_arc), without
        the feeds' cap."""
        a, b = (Block((0, 0), u, 0, U32, 0, 0, 0) for u in (u1, u2))
        return junction(a, b, self.cfg)

    def push_arc(self, pts, r: int, feed: int, tool: int, index: int) -> bool:
        """An arc from the last point through the chord ends pts (radius r um) as one block
        (planner_arc's rules); False (nothing queued) where planner_arc keeps it chords."""
        if self.cross_jmax:
            raise ValueError("an arc block needs MachineConfig.arc_blocks (the sampler's rule for arcs: no brake "
                             "credit, block ends at most at their exits)")
        got = arc_chords(self.last, pts, r, self.acc, length_q, self.vertex)
        if got is None:
            return False
        ch, acc, vcap = got
        l16 = ch.s0[-1] + ch.l16[-1]
        vn = min((min(feed, self.cfg.max_feed_um_min) << 16) // (60 * self.cfg.sample_hz), vcap)
        self._queue(Block(tuple(pts[-1]), ch.u[0], l16 >> 16, vn, acc, tool, index, l16 & 0xFFFF,
                          u_out=ch.u[-1], chords=ch))
        return True

    def _backward(self) -> None:
        q = self.q
        q[-1].exit = 0
        for k in range(len(q) - 2, -1, -1):
            b, n = q[k], q[k + 1]
            a = brake_acc(q, k)
            t = a * n.len + ((a * n.lfr) >> 16)
            ex = b.jmax - self.alpha if b.jmax > self.alpha else 0  # crossed at most alpha above it
            if t < 1 << 40:
                e2 = n.exit * n.exit + (t << 17)
                if ex * ex > e2:
                    ex = isqrt(e2)
            if ex < b.acc >> 2:
                ex = 0  # below the sampler's floor: a stop
            if ex == b.exit:
                return
            b.exit = ex

    @staticmethod
    def _can_brake(c: int, rem: int, ve: int, acc: int, alpha: int) -> bool:
        """nnik_plan_sample.c can_brake: c <= ve + alpha (toward a stop, ve = 0: c <= acc), or
        2 acc (rem - c) >= x^2 - ve^2 with x = c - alpha toward a junction, c - floor(acc / 2)
        toward a stop (the sampler's own steps down, then it lands), rounded against it (acc / 32,
        D in 1/32 um)."""
        if c <= (ve + alpha if ve else acc):
            return True
        if rem <= c:
            return False
        d = (rem - c) >> 16
        if d > U32 // (2 * acc):
            return True
        cq, eq = (c - (alpha if ve else acc >> 1) + 511) >> 9, ve >> 9
        p = cq * cq - eq * eq
        return ((acc >> 5) * ((rem - c) >> 11)) >> 1 >= p

    def can_go(self, c: int, rem: int) -> bool:
        """nnik_plan_sample.c can_go: each block end the sample reaches (rem <= c) it lands on when
        it is a stop (exit 0) and rem <= that block's acc, else passes at most at the junction's
        limit (jmax; at most at the exit where cross_jmax is False), and the block it
        ends in can still brake."""
        q, k = self.q, 0
        while rem <= c:
            b = q[k]
            if not b.exit:
                return rem <= b.acc
            if c > (b.jmax if self.cross_jmax else b.exit):
                return False
            k += 1
            rem += q[k].l16
        return self._can_brake(c, rem, q[k].exit, q[k].acc, self.alpha)

    def fastest(self, lo: int, hi: int, rem: int) -> int:
        """nnik_plan_sample.c fastest(): from lo (may go) toward hi (may not), lo + d for
        d = (hi - lo) >> 1, halved each time, 4 times (or until d is 0), kept where it may go."""
        d = (hi - lo) >> 1
        for _ in range(4):
            if not d:  # the chip tries lo itself then, which changes nothing
                break
            if self.can_go(lo + d, rem):
                lo += d
            d >>= 1
        return lo

    def slower(self, up: int, v: int, rem: int) -> int:
        """The sample's speed from speed v when up (v + acc, at most vn) may not go
        (nnik_plan_sample.c nnik_pl_sample()): hold (min(v, vn)) when it may go, else down (v - acc,
        or the exit when it lies between and may go), at least max(acc >> 2, 1); with
        MachineConfig.speed_search the fastest between hold and up, or between down (when it may
        go) and hold (up when hold is 0)."""
        b, search = self.q[0], self.cfg.speed_search
        c = min(v, b.vn)  # hold (not at rest: the sample must move)
        if c and c < up and self.can_go(c, rem):  # (hold = up may not go)
            return self.fastest(c, up, rem) if search else c
        hi = c if c else up
        c = v - b.acc if v > b.acc else 0
        if c < b.exit < v and self.can_go(b.exit, rem):
            c = b.exit  # down to the exit if it may go at it
        if search and c and self.can_go(c, rem):
            c = self.fastest(c, hi, rem)
        return max(c, b.acc >> 2, 1)

    def sample(self) -> tuple[tuple[int, int], int, int, int, int]:
        """One sample: (point, speed used, its block's vn, tool word, push index)."""
        b = self.q[0]
        s, v = self.s, self.v
        rem = b.l16 - s
        if v < b.vn:
            c = min(v + b.acc, b.vn)
        elif v > b.vn:
            c = v - b.acc if (v > b.acc and v - b.acc > b.vn) else b.vn
        else:
            c = v
        if not self.can_go(c, rem):
            c = self.slower(c, v, rem)
        used = self.moved = c  # moved: the path length of the sample (nnik_pl_sample_t.moved)
        s += c
        stop = False
        while s >= b.l16:
            self.start = b.end
            self.q.pop(0)
            if not b.exit or not self.q:
                stop, s, c, self.moved = True, 0, 0, used - (s - b.l16)
                break
            s -= b.l16
            b = self.q[0]
        self.v, self.s = c, s
        if stop:
            p = b.end
        elif b.chords is not None:
            p = arc_point(b.chords, s)
        else:
            su = s >> 16
            p = (self.start[0] + ((b.u[0] * su) >> 30), self.start[1] + ((b.u[1] * su) >> 30))
        return p, used, b.vn, b.tool, b.index


def push_arc_op(pl: Planner, op: tuple) -> None:
    """("arc", x, y, feed, tool, index, points, r): the interpreter emits it only for an arc
    that planner_arc makes one block."""
    if not pl.push_arc(op[6], op[7], op[3], op[4], op[5]):
        raise ValueError("an arc operation that planner_arc keeps as chords")


class Shaper:
    """nnik_shaper.c: shaped = p + ((16384 - sum A_i (p[n] - p[n - d_i])) >> 15) per axis."""

    def __init__(self, cfg: MachineConfig, p=(0, 0)):
        self.taps = cfg.shaper_taps
        self.hist = [list(), list()]  # the last shaper_len + 1 inputs per axis, newest last
        self.n = cfg.shaper_len
        for a in range(2):
            self.hist[a] = [p[a]] * (self.n + 1)

    def step(self, p) -> tuple[int, int]:
        if not self.n:
            return tuple(p)
        out = []
        for a in range(2):
            h = self.hist[a]
            h.pop(0)
            h.append(p[a])
            amps, delays = self.taps[a]
            acc = 16384 - sum(A * (p[a] - h[-1 - d]) for A, d in zip(amps, delays) if d)
            out.append(p[a] + (acc >> 15))
        return out[0], out[1]


@dataclass
class Stream:
    """The stepper segments before the IK: one per sample (kind 0) or rest (kind 1)."""

    kind: list[int] = field(default_factory=list)
    planned: list[tuple[int, int]] = field(default_factory=list)  # the planner's point (um)
    shaped: list[tuple[int, int]] = field(default_factory=list)  # what the IK gets (um, less origin)
    speed: list[int] = field(default_factory=list)  # planned speed of the sample, Q16 um/sample
    vn: list[int] = field(default_factory=list)
    tool: list[int] = field(default_factory=list)  # tool word (samples) or fixed duty word (rests)
    rest_ticks: list[int] = field(default_factory=list)  # 0 for samples
    block: list[int] = field(default_factory=list)  # push index of the sample's block (-1: rest)
    moved: list[int] = field(default_factory=list)  # path length of the sample, Q16 um (0: tail, rest)


def run_ops_reference(ops: list[tuple], cfg: MachineConfig) -> Stream:
    """run_ops one sample at a time through Planner.sample and Shaper.step (the definition the
    bulk sampler is checked against)."""
    pl, sh, st = Planner(cfg), Shaper(cfg), Stream()
    settle, tail_tool = 0, 0

    def out(p, tool, v, vn, blk, kind=0, ticks=0, moved=0):
        st.kind.append(kind)
        st.moved.append(moved)
        st.planned.append(tuple(p))
        st.shaped.append(sh.step(p) if kind == 0 else st.shaped[-1] if st.shaped else (0, 0))
        st.speed.append(v)
        st.vn.append(vn)
        st.tool.append(tool)
        st.rest_ticks.append(ticks)
        st.block.append(blk)

    def sample():
        nonlocal settle, tail_tool
        p, v, vn, tool, idx = pl.sample()
        settle, tail_tool = cfg.shaper_len, tool
        out(p, tool, v, vn, idx, moved=pl.moved)

    def flush():
        nonlocal settle
        while pl.ready(True):
            sample()
        while settle:
            settle -= 1
            out(pl.start, tail_tool, 0, 1, -1)

    for op in ops:
        if op[0] == "push":
            while pl.ready(False):
                sample()
            pl.push(op[1], op[2], op[3], op[4], op[5])
        elif op[0] == "arc":
            while pl.ready(False):
                sample()
            push_arc_op(pl, op)
        elif op[0] == "flush":
            flush()
        else:
            flush()
            out(pl.start, op[2], 0, 1, -1, kind=1, ticks=op[1])
    flush()
    return st


def duty_of(stream: Stream, cfg: MachineConfig | None = None) -> np.ndarray:
    """OCR2A per segment: the tool word's duty, M4 (0x100) scaled by min(v, vn) / vn; with cfg's
    shaper, in step with the shaped head (nnik.firmware.gcode.tool_shaper)."""
    return stream_duty(stream.kind, stream.speed, stream.vn, stream.tool, stream.moved, cfg)
