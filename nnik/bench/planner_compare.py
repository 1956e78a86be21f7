"""The firmware's integer planner (nnik.firmware.gcode.planner, bit for bit nnik_plan.c) measured
against the float grbl oracle (nnik.bench.planner_oracle) on the same operations and limits.

How the integer planner's figures are read from its sample stream.  The sampler is replayed
sample by sample (Planner.sample, as planner.run_ops_reference does, without the shaper) and for
each sample we keep the speed it used, c (Q16 um/sample: the distance it advances along the
path), the block it started in, and the blocks it left behind (several on chords shorter than a
sample's travel).  With the unit vector normalised (|u| <= 1, the point start + u s), the
distance along a block is the path's own arclength, so c is the sample's path speed; the point
itself is that arclength rounded down to whole um (the stepper's resolution), which is why the
speeds are not taken from differences of points (their +-1 um would swamp an acceleration of
about 1 um per sample^2).

* Junction speed: the speed of the sample that passes the junction (the first sample that
  reaches or leaves the end of the block before it).  The motion between two samples is one
  straight stepper segment at constant speed, so that sample's speed is the speed at which the
  machine goes through the corner.  When the planner stops at the junction (exit speed 0: the
  sample lands exactly on the end and the next one starts from rest) the junction speed is 0.
* Acceleration: the change of speed from one sample to the next, |c_k - c_{k-1}| per sample^2
  (c_{k-1} = 0 after a stop), belongs to the block sample k starts in (its rule picked c_k);
  along a straight block the per-sample displacement is c u, so each axis changes by
  |c_k - c_{k-1}| |u_axis| and every axis stays within its limit exactly when the change is at
  most grbl's block acceleration min_axis a_axis / |u_axis| (the oracle's).  A sample that ends
  in a stop advances only the distance left, d <= c; the step down from d to rest is counted too.
* Job time: samples * (1 / sample_hz) against the float plan's trapezoid times.

* Arc cap: the speed of each sample that starts in an arc block against the float arc's cap (its
  centripetal limit and every inner vertex's grbl limit, nnik.bench.planner_oracle; the feed aside).

Ratios: junction = integer / float limit (a float limit of 0 with an integer stop is 0), accel
= integer change / block acceleration, arc_cap = speed / the arc's float cap, time = integer / float.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nnik.bench import planner_oracle as oracle
from nnik.firmware.gcode.planner import Planner, push_arc_op


@dataclass
class Measured:
    """Per sample: speed used (Q16), head block's push index at its start, the blocks it left
    (indices), whether it ended in a stop, and the distance it advanced (Q16)."""

    speed: list[int] = field(default_factory=list)
    head: list[int] = field(default_factory=list)
    passed: list[list[int]] = field(default_factory=list)
    stop: list[bool] = field(default_factory=list)
    advance: list[int] = field(default_factory=list)


def replay(ops: list[tuple], cfg) -> Measured:
    """Play push / flush / rest ops through the integer planner as the firmware does (sample
    while the queue is full before a push, drain to rest at a flush or rest)."""
    pl, m, lens = Planner(cfg), Measured(), {}

    def sample():
        head, s0 = pl.q[0], pl.s
        before = [b.index for b in pl.q]
        _, used, _, _, _ = pl.sample()
        gone = before[:len(before) - len(pl.q)]
        stop = bool(gone) and pl.v == 0
        m.speed.append(used)
        m.head.append(head.index)
        m.passed.append(gone)
        m.stop.append(stop)
        # a stop advances only the rest of its head block and of the blocks it crossed whole
        m.advance.append(used if not stop else head.l16 - s0 + sum(lens[i] for i in gone[1:]))

    for op in ops:
        if op[0] == "push":
            while pl.ready(False):
                sample()
            n = len(pl.q)
            pl.push(op[1], op[2], op[3], op[4], op[5])
            if len(pl.q) > n:
                lens[op[5]] = pl.q[-1].l16
        elif op[0] == "arc":
            while pl.ready(False):
                sample()
            push_arc_op(pl, op)
            lens[op[5]] = pl.q[-1].l16
        else:
            while pl.ready(True):
                sample()
    while pl.ready(True):
        sample()
    return m


def compare(ops: list[tuple], cfg, lookahead: int | None = -1) -> dict:
    """The integer planner against the float oracle: per-junction and per-sample ratios and the
    job-time ratio (see the module's docstring)."""
    fp = oracle.plan(ops, cfg, lookahead)
    blocks = {b.index: b for run in fp.runs for b in run}
    nxt = {run[k].index: run[k + 1].index for run in fp.runs for k in range(len(run) - 1)}
    m = replay(ops, cfg)
    hz = cfg.sample_hz
    to_um_s = hz / 65536.0
    junction = []
    for k, gone in enumerate(m.passed):
        for j, idx in enumerate(gone):
            if idx not in nxt:
                continue  # the end of a run: a stop at rest, no junction
            lim = blocks[nxt[idx]].entry_max
            last = j == len(gone) - 1
            v = 0.0 if (m.stop[k] and last) else m.speed[k] * to_um_s
            junction.append(v / lim if lim > 0 else (0.0 if v == 0 else np.inf))
    accel, prev = [], 0
    for k, c in enumerate(m.speed):
        a = blocks[m.head[k]].acc
        d = m.advance[k]
        accel.append(abs(d - prev) * to_um_s * hz / a)
        if m.stop[k]:
            accel.append(d * to_um_s * hz / blocks[m.passed[k][-1]].acc)
            prev = 0
        else:
            prev = d
    t_int = len(m.speed) / hz
    arc_cap = [c * to_um_s / blocks[h].cap for c, h in zip(m.speed, m.head) if blocks[h].cap < np.inf]
    return {"junction": np.asarray(junction, dtype=float), "accel": np.asarray(accel, dtype=float),
            "arc_cap": np.asarray(arc_cap, dtype=float),
            "time_int_s": t_int, "time_float_s": fp.time_s,
            "time_ratio": t_int / fp.time_s if fp.time_s > 0 else 1.0}
