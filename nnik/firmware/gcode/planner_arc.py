"""An arc (G2/G3 in G17) as ONE planner block, cut into its chords only by the sampler (the rules;
nnik_plan.h states them for the chip, bit for bit with this).

The interpreter cuts the arc into chords as before (nnik.firmware.gcode.geometry.arc_points:
chords of at most seg_um).  With MachineConfig.arc_blocks it hands them to the planner as one
("arc", x, y, feed, tool, index, points, r) operation instead of one push per chord.  The block:

* its chords are the line blocks' pieces: for the chord d = q - p, (Lq, Lc, f) = length_q(d),
  its length l16 = floor(sqrt(n) 2^16) (Q16 um) and its unit vector u = trunc(|d| 2^(30+f) / Lc)
  with d's sign, as nnik_pl_push computes a line's; zero chords are dropped;
* length = the exact sum of its chords' l16 (len = that >> 16, lfr = that & 0xFFFF), so the
  sampler's distance along the block is the chords' own and the last chord ends on the block's end;
* junctions with the blocks before and after: grbl's rule (planner.junction) with the first
  chord's u on entry and the last chord's u on exit; the vertices inside get no junction limit;
* acceleration (tangential) acc = floor(amin 46340 / 2^16), amin = min(acc_q16 of the two
  axes), 46340 / 2^16 < 1 / sqrt(2): the speed changes by at most amin / sqrt(2) per sample;
* nominal speed vn = min(F's vn, the centripetal cap, every inner vertex's junction limit):
  the centripetal cap isqrt(amin re 46340) (Q16 um / sample, re = r - 1 um: v^2 / r <=
  amin / sqrt(2), so the tangential and the centripetal acceleration, at right angles, sum to at
  most amin along the circle: every axis within its own limit), and at
  each vertex between two chords the line blocks' junction rule (planner.junction on the two
  chords, rounded down, at most grbl's float limit for that vertex): the vertices inside get no
  junction of their own, the block never passes one faster than grbl would;
* it stays chords (one line block each, as without arc_blocks) when it has fewer than 2 chords,
  when a chord turns the path too much (4 ch > r, ch the longest chord's whole um + 1) or when
  vn is at or below the sampler's floor (acc >> 2): a coarse polygon is planned as the polygon
  it is.

The sampler walks the head block's chords in order: at distance s along the block, in the chord
that starts at s0 (s0 <= s < s0 + l16), the point is the chord's start + (u * floor((s - s0) /
2^16)) >> 30 per axis (the line's formula), the block's end once s reaches its length.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass
from math import isqrt


@dataclass(frozen=True)
class Chords:
    """The chords of an arc block: each one's start distance s0 (Q16 um), start point, unit
    vector (Q30) and length l16 (Q16 um)."""

    s0: tuple[int, ...]
    start: tuple[tuple[int, int], ...]
    u: tuple[tuple[int, int], ...]
    l16: tuple[int, ...]


def chord_piece(dx: int, dy: int, length_q) -> tuple[int, tuple[int, int]]:
    """(l16, u) of the chord (dx, dy) != 0, as nnik_pl_push computes a line block's."""
    Lq, Lc, f = length_q(dx, dy)
    l16 = Lq >> (f - 16) if f >= 16 else Lq << (16 - f)
    u = tuple((abs(d) << (30 + f)) // Lc * (-1 if d < 0 else 1) for d in (dx, dy))
    return l16, u


def arc_chords(last: tuple[int, int], pts, r: int, acc_q16, length_q, vertex):
    """(Chords, acc, vcap) of the arc from last through pts, or None when it stays chords;
    vertex(u1, u2) is the junction limit between two chords (Q16 um / sample)."""
    s0, start, us, ls = [], [], [], []
    p, s = last, 0
    for q in pts:
        dx, dy = q[0] - p[0], q[1] - p[1]
        if dx or dy:
            l16, u = chord_piece(dx, dy, length_q)
            s0.append(s)
            start.append(p)
            us.append(u)
            ls.append(l16)
            s += l16
            p = q
    if len(ls) < 2 or 4 * ((max(ls) >> 16) + 1) > r:
        return None
    amin = min(acc_q16)
    acc = (amin * 46340) >> 16
    vcap = isqrt(amin * max(r - 1, 1) * 46340)
    for k in range(1, len(us)):
        vcap = min(vcap, vertex(us[k - 1], us[k]))
    if vcap <= acc >> 2:
        return None
    return Chords(tuple(s0), tuple(start), tuple(us), tuple(ls)), acc, vcap


def arc_point(ch: Chords, s: int) -> tuple[int, int]:
    """The point at distance s (Q16 um, below the block's length) along the chords."""
    i = bisect_right(ch.s0, s) - 1
    su = (s - ch.s0[i]) >> 16
    st, u = ch.start[i], ch.u[i]
    return st[0] + ((u[0] * su) >> 30), st[1] + ((u[1] * su) >> 30)


def last_end(ops: list) -> tuple[int, int]:
    """Where the planner stands after ops: the last push's or arc's end, (0, 0) before any."""
    for op in reversed(ops):
        if op[0] in ("push", "arc"):
            return op[1], op[2]
    return 0, 0


def as_arc_op(ops: list, k0: int, r: int, acc_q16, length_q, vertex, k1: int | None = None) -> None:
    """ops[k0:k1] (the pushes of one arc's chords, radius r um) become one ("arc", x, y, feed,
    tool, index, points, r) operation when the arc is one block by the rules above."""
    k1 = len(ops) if k1 is None else k1
    new = ops[k0:k1]
    if len(new) < 2 or any(op[0] != "push" for op in new):
        return
    pts = tuple((op[1], op[2]) for op in new)
    if arc_chords(last_end(ops[:k0]), pts, r, acc_q16, length_q, vertex) is None:
        return
    ops[k0:k1] = [("arc",) + new[-1][1:3] + new[0][3:6] + (pts, r)]
