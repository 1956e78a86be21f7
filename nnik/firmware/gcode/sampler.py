"""The planner's operations as arrays (run_ops): the same planner, sampler and shaper, in fewer Python steps.

What the chip does per sample (nnik_plan_sample.c, planner.Planner.sample) is kept rule for rule; two
things make it fast without changing a bit:

* cruise runs in bulk: at the block's feed (speed = vn) each sample is c = vn as long as the brake
  test passes and the block does not end; the brake test is monotone in the distance left, so
  the run's length is found by bisection and its points are computed at once with numpy (the
  same integer formula, start + (u * (s >> 16)) >> 30, floor shifts on both sides);
* the input shaper is a FIR over the sample stream (rests do not step it), so it runs after the
  sampler, vectorised: shaped = p + ((16384 - sum A_i (p[n] - p[n - d_i])) >> 15), p before the
  first sample = the start (0, 0), as planner.Shaper.step.

run_arrays(ops, cfg) -> Arrays; run_ops turns them into planner's Stream of lists.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.planner import U32, Planner, Stream, push_arc_op
from nnik.firmware.gcode.planner_arc import arc_point

BULK_MIN = 8  # cruise runs at least this long go through numpy


@dataclass
class Arrays:
    """The stream of planner.Stream as numpy arrays (one row per stepper segment)."""

    kind: np.ndarray  # (S,) 0: a sample, 1: a rest
    planned: np.ndarray  # (S, 2)
    shaped: np.ndarray  # (S, 2)
    speed: np.ndarray  # (S,)
    vn: np.ndarray  # (S,)
    tool: np.ndarray  # (S,)
    rest_ticks: np.ndarray  # (S,)
    block: np.ndarray  # (S,)
    moved: np.ndarray  # (S,) path length of the sample, Q16 um (0: the shaper's tail, a rest)


_brakes = Planner._can_brake  # the brake test, as the chip does it (inlined below where it is hot)


def _cruise_len(c: int, rem: int, ve: int, acc: int, alpha: int, most: int) -> int:
    """How many samples j = 0.. at speed c pass the brake test with rem - j c left (at most
    most): the test is monotone in the distance left, so bisect for the first that fails."""
    if _brakes(c, rem - (most - 1) * c, ve, acc, alpha):
        return most
    lo, hi = 0, most - 1  # passes at lo (checked by the caller), fails at hi
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if _brakes(c, rem - mid * c, ve, acc, alpha):
            lo = mid
        else:
            hi = mid
    return hi


def _drain(pl: Planner, flushing: bool, X: list, Y: list, V: list, B: list, stops: dict) -> None:
    """Sample while the queue is ready (full, or not empty when flushing), appending each
    sample's point, speed used and block push index; stops[row]: the path length moved by a
    sample that stops (the others move their speed)."""
    q, n, alpha = pl.q, pl.n, pl.alpha
    s, v = pl.s, pl.v
    while q and (flushing or len(q) == n):
        b = q[0]
        L16, vn, acc, ex, idx = b.l16, b.vn, b.acc, b.exit, b.index
        ux, uy = b.u
        sx, sy = pl.start
        arc = b.chords  # an arc block: its points along its chords (planner_arc)
        while True:
            rem = L16 - s
            if v < vn:
                c = v + acc
                if c > vn:
                    c = vn
            elif v > vn:
                c = v - acc if (v > acc and v - acc > vn) else vn
            else:
                c = v
                most = (rem - 1) // c if c else 0  # samples at c that stay inside the block
                if most >= BULK_MIN and arc is None and _brakes(c, rem, ex, acc, alpha):
                    k = _cruise_len(c, rem, ex, acc, alpha, most)
                    su = (s + c * np.arange(1, k + 1, dtype=np.int64)) >> 16
                    X.extend((sx + ((ux * su) >> 30)).tolist())
                    Y.extend((sy + ((uy * su) >> 30)).tolist())
                    V.extend([c] * k)
                    B.extend([idx] * k)
                    s += k * c
                    continue
            # the brake test (Planner.can_go; inline while the sample stays in its block), then
            # Planner.slower (hold, down, the fastest between, the floor)
            if rem <= c:
                ok = pl.can_go(c, rem)
            else:
                ok = (ex and c <= ex + alpha) or _brakes(c, rem, ex, acc, alpha)
            if not ok:
                c = pl.slower(c, v, rem)
            s += c
            if s < L16:
                su = s >> 16
                if arc is not None:
                    px, py = arc_point(arc, s)
                    X.append(px)
                    Y.append(py)
                else:
                    X.append(sx + ((ux * su) >> 30))
                    Y.append(sy + ((uy * su) >> 30))
                V.append(c)
                B.append(idx)
                v = c
                continue
            # the head block is left behind (Planner.sample's loop)
            used, stop = c, False
            while s >= b.l16:
                pl.start = b.end
                q.pop(0)
                if not b.exit or not q:
                    stops[len(V)] = used - (s - b.l16)  # the path length left, not c
                    stop, s, c = True, 0, 0
                    break
                s -= b.l16
                b = q[0]
            v = c
            if stop:
                X.append(b.end[0])
                Y.append(b.end[1])
            elif b.chords is not None:
                px, py = arc_point(b.chords, s)
                X.append(px)
                Y.append(py)
            else:
                su = s >> 16
                X.append(pl.start[0] + ((b.u[0] * su) >> 30))
                Y.append(pl.start[1] + ((b.u[1] * su) >> 30))
            V.append(used)
            B.append(b.index)
            break
    pl.s, pl.v = s, v


def _shape(p: np.ndarray, cfg: MachineConfig) -> np.ndarray:
    """planner.Shaper over the samples p (N, 2), from rest at (0, 0)."""
    n = cfg.shaper_len
    if not n or not len(p):
        return p.copy()
    out = np.empty_like(p)
    for a in range(2):
        h = np.concatenate([np.zeros(n, np.int64), p[:, a]])
        cur = h[n:]
        acc = np.full(len(p), 16384, np.int64)
        amps, delays = cfg.shaper_taps[a]
        for A, d in zip(amps, delays):
            if d:
                acc -= A * (cur - h[n - d:len(h) - d])
        out[:, a] = cur + (acc >> 15)
    return out


def run_arrays(ops: list[tuple], cfg: MachineConfig) -> Arrays:
    """ops as run_ops takes them; the same stream, as arrays."""
    pl = Planner(cfg)
    X, Y, V, B = [], [], [], []
    stops = {}  # row: the path length of a sample that stops
    special = []  # (row, kind, tool, ticks) of the shaper's tail samples and the rests
    tail = cfg.shaper_len
    state = {"sampled": False, "tail_tool": 0, "rows": 0}
    vn_of, tool_of = {}, {}

    def flush():
        _drain(pl, True, X, Y, V, B, stops)
        if len(X) > state["rows"]:  # samples since the last tail: the tail tool is the last one's
            state["sampled"], state["tail_tool"], state["rows"] = True, tool_of[B[-1]], len(X)
        if state["sampled"] and tail:
            for _ in range(tail):
                special.append((len(X), 0, state["tail_tool"], 0))
                X.append(pl.start[0])
                Y.append(pl.start[1])
                V.append(0)
                B.append(-1)
            state["rows"] = len(X)
        state["sampled"] = False

    for op in ops:
        if op[0] == "push":
            if len(pl.q) == pl.n:
                _drain(pl, False, X, Y, V, B, stops)
            vn_of[op[5]] = (min(op[3], cfg.max_feed_um_min) << 16) // (60 * cfg.sample_hz)
            tool_of[op[5]] = op[4]
            pl.push(op[1], op[2], op[3], op[4], op[5])
        elif op[0] == "arc":
            if len(pl.q) == pl.n:
                _drain(pl, False, X, Y, V, B, stops)
            push_arc_op(pl, op)
            vn_of[op[5]] = pl.q[-1].vn  # the arc's capped nominal speed
            tool_of[op[5]] = op[4]
        elif op[0] == "flush":
            flush()
        else:
            flush()
            special.append((len(X), 1, op[2], op[1]))
            X.append(pl.start[0])
            Y.append(pl.start[1])
            V.append(0)
            B.append(-1)
            state["rows"] = len(X)
    flush()
    return _assemble(X, Y, V, B, stops, special, vn_of, tool_of, cfg)


def _assemble(X, Y, V, B, stops, special, vn_of, tool_of, cfg) -> Arrays:
    N = len(X)
    planned = np.empty((N, 2), np.int64)
    planned[:, 0], planned[:, 1] = X, Y
    block = np.asarray(B, dtype=np.int64)
    kind = np.zeros(N, np.int64)
    rest_ticks = np.zeros(N, np.int64)
    keys = sorted(vn_of)
    lut_vn = np.ones(max(keys, default=0) + 2, np.int64)  # index -1 (last slot): vn 1
    lut_tool = np.zeros(len(lut_vn), np.int64)
    if keys:
        lut_vn[keys] = [vn_of[k] for k in keys]
        lut_tool[keys] = [tool_of[k] for k in keys]
    vn, tool = lut_vn[block], lut_tool[block]
    for row, k, t, ticks in special:
        kind[row], tool[row], rest_ticks[row] = k, t, ticks
    samp = kind == 0
    shaped = np.empty_like(planned)
    shaped[samp] = _shape(planned[samp], cfg)
    if (~samp).any():  # a rest keeps the shaped point before it ((0, 0) first)
        last = np.where(samp, np.arange(N), -1)
        last = np.maximum.accumulate(last)
        held = np.zeros((N, 2), np.int64)
        ok = last >= 0
        held[ok] = shaped[last[ok]]
        shaped[~samp] = held[~samp]
    speed = np.asarray(V, dtype=np.int64)
    moved = speed.copy()  # the tail and the rests: speed 0
    moved[list(stops)] = list(stops.values())
    return Arrays(kind, planned, shaped, speed, vn, tool, rest_ticks, block, moved)


def run_ops(ops: list[tuple], cfg: MachineConfig) -> Stream:
    """ops: ("push", x, y, feed, tool, index), ("flush",), ("rest", ticks, tool).  The stream
    as nnik_gc_segments.c makes it: Planner.sample and Shaper.step rule for rule, run in bulk here
    (planner.run_ops_reference is the sample-by-sample loop)."""
    a = run_arrays(ops, cfg)
    pairs = lambda m: list(zip(m[:, 0].tolist(), m[:, 1].tolist()))  # noqa: E731
    return Stream(a.kind.tolist(), pairs(a.planned), pairs(a.shaped), a.speed.tolist(), a.vn.tolist(),
                  a.tool.tolist(), a.rest_ticks.tolist(), a.block.tolist(), a.moved.tolist())
