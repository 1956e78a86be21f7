"""grbl's float planner (nnik.bench.planner_oracle: the same blocks, limits and rules) run on the
chip's sample clock: the reference the integer planner's job time is held to.

The oracle's continuous model takes block i + N into its lookahead the instant the head leaves
block i.  A planner fed by a fixed-rate sampler cannot: its queue moves on only between samples
(the chip pushes the next block after the sample that left the head behind), so during a sample
the motion may use only the blocks that were queued when the sample began.  Here the motion is
still continuous and float (time-optimal: accelerate at the block's acceleration up to the least
of its nominal speed and the braking curve to the last queued block's end at rest, ride that
curve, cross each junction at most at its exit), but the queue is refreshed only at sample
instants: at each instant the head is the block the motion is in, and the plan is the head and
the N - 1 blocks after it, the last ending at rest, exactly the chip's queue at that sample.

Where a sample travels a small part of the lookahead's length the two float models agree; on
chords short against a sample's travel with few blocks, no sampler can match the continuous one,
and the difference is what the fixed clock costs (`make bench` prints it beside the integer
planner's ratios).  Speeds um/s, accelerations um/s^2, times s.
"""

from __future__ import annotations

import math

from nnik.bench import planner_oracle as oracle

_EPS = 1e-9


def _exits(L, acc, jm, j: int, last: int) -> dict[int, float]:
    """The float backward pass over blocks j..last, the last ending at rest."""
    x, e = {last: 0.0}, 0.0
    for k in range(last - 1, j - 1, -1):
        e = min(jm[k + 1], math.sqrt(e * e + 2.0 * acc[k + 1] * L[k + 1]))
        x[k] = e
    return x


def run_time(run: list[oracle.FBlock], n: int, hz: float, trace: list | None = None) -> float:
    """The time of one run (blocks from rest to rest) with an n-block queue refreshed at the
    sample instants (1 / hz apart); trace (a list) gets (block, distance along it, speed) at each
    instant."""
    L = [b.length for b in run]
    acc = [b.acc for b in run]
    vn = [b.vn for b in run]
    jm = [b.entry_max for b in run]
    m, dt = len(run), 1.0 / hz
    j, y, v, t = 0, 0.0, 0.0, 0.0
    while True:
        while y >= L[j] - _EPS and j < m - 1:
            j, y = j + 1, 0.0  # the head is the block the motion is in
        if trace is not None:
            trace.append((run[j].index, y, v))
        last = min(m - 1, j + n - 1)
        x = _exits(L, acc, jm, j, last)
        tau = dt
        while tau > 0.0:
            a, V, X, rem = acc[j], vn[j], x[j], max(L[j] - y, 0.0)
            B = math.sqrt(X * X + 2.0 * a * rem)
            U = min(V, B)
            if rem <= _EPS:
                if j == last:  # at rest on the queue's end: the run's end, or wait for the sample
                    if last == m - 1:
                        return t + (dt - tau)
                    tau = 0.0
                    v = 0.0
                    break
                j, y = j + 1, 0.0
                continue
            if v < U * (1.0 - 1e-12) - _EPS:  # accelerate
                t_v = (V - v) / a
                t_b = (-v + math.sqrt(max((v * v + X * X + 2.0 * a * rem) / 2.0, 0.0))) / a
                t_e = (-v + math.sqrt(v * v + 2.0 * a * rem)) / a
                h = min(t_v, t_b, t_e, tau)
                y += v * h + 0.5 * a * h * h
                v = min(v + a * h, U)
                if h == t_e:
                    y = L[j]
            elif V <= B and rem - max((V * V - X * X) / (2.0 * a), 0.0) > _EPS:
                v = V  # cruise at the nominal speed until the braking curve (or the block's end)
                d = rem - max((V * V - X * X) / (2.0 * a), 0.0)
                h = min(d / V, tau)
                y += V * h
                if h == d / V and d >= rem - _EPS:
                    y = L[j]
            else:  # ride the braking curve (from its foot, too) to the block's exit
                v = U
                h = min((v - X) / a, tau)
                if h <= 0.0:
                    y = L[j]
                    continue
                y += v * h - 0.5 * a * h * h
                v -= a * h
                if h == (U - X) / a:
                    y, v = L[j], X
            tau -= h
        t += dt


def plan_time(ops: list[tuple], cfg, lookahead: int | None = -1) -> float:
    """The job's motion time (s) with the chip's queue (cfg.lookahead blocks, or `lookahead`)
    refreshed at its sample instants."""
    n = cfg.lookahead if lookahead == -1 else lookahead
    return sum(run_time(run, n if n is not None else len(run), float(cfg.sample_hz))
               for run in oracle.blocks_of(ops, cfg))
