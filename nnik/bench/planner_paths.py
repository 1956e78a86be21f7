"""Paths for the planner comparisons (tests and `make bench`): lines turning by given angles
(corners), arcs cut into chords of a given length (CAM curves), reversals; as the interpreter's
push operations in whole um, ending with a flush."""

from __future__ import annotations

import math

from nnik.firmware.gcode.planner import Planner, length_q
from nnik.firmware.gcode.planner_arc import as_arc_op


def path_ops(pieces: list[tuple], feed_um_min: int, start_deg: float = 0.0, arcs: list | None = None) -> list[tuple]:
    """pieces: ("line", length_um, turn_deg) turns the heading by turn_deg then goes straight;
    ("arc", radius_um, sweep_deg, chord_um) follows an arc (left for a positive sweep) tangent to
    the heading, in chords of about chord_um; ("rev", length_um) goes back the way it came.
    arcs (a list) gets (first op, end op, radius um) of each arc piece."""
    x = y = 0.0
    h = math.radians(start_deg)
    pts = []
    for p in pieces:
        if p[0] == "line":
            h += math.radians(p[2])
            x, y = x + p[1] * math.cos(h), y + p[1] * math.sin(h)
            pts.append((x, y))
        elif p[0] == "rev":
            h += math.pi
            x, y = x + p[1] * math.cos(h), y + p[1] * math.sin(h)
            pts.append((x, y))
        else:
            _, r, sweep, chord = p
            side = 1.0 if sweep >= 0 else -1.0
            cx, cy = x - side * r * math.sin(h), y + side * r * math.cos(h)
            a0 = math.atan2(y - cy, x - cx)
            total = math.radians(abs(sweep))
            n = max(1, round(total * r / chord))
            if arcs is not None:
                arcs.append((len(pts), len(pts) + n, int(r)))
            for k in range(1, n + 1):
                a = a0 + side * total * k / n
                pts.append((cx + r * math.cos(a), cy + r * math.sin(a)))
            x, y = pts[-1]
            h += side * total
    ops = [("push", int(round(px)), int(round(py)), feed_um_min, 0, i) for i, (px, py) in enumerate(pts)]
    return ops + [("flush",)]


def arc_block_ops(pieces: list[tuple], feed_um_min: int, cfg) -> list[tuple]:
    """path_ops with each arc piece as one arc operation where planner_arc makes it one block
    (cfg's limits), else its chords."""
    spans: list = []
    ops = path_ops(pieces, feed_um_min, arcs=spans)
    vertex = Planner(cfg).vertex
    for k0, k1, r in reversed(spans):
        as_arc_op(ops, k0, r, cfg.acc_q16, length_q, vertex, k1)
    return ops


def chord_ops(chord_um: float, radius_um: float, turns: float, feed_um_min: int) -> list[tuple]:
    """A spiral-free circle job: `turns` turns of a circle of radius_um in chords of chord_um."""
    return path_ops([("arc", radius_um, 360.0 * turns, chord_um)], feed_um_min)


def random_pieces(rng, n: int = 40) -> list[tuple]:
    """n random pieces (numpy Generator): corners with lines of 0.02-5 mm, arcs of 0.2-20 mm
    radius in 0.01-0.2 mm chords, reversals, short nearly straight lines."""
    out = []
    for _ in range(n):
        k = int(rng.integers(0, 4))
        if k == 0:
            out.append(("line", float(rng.uniform(20, 5000)), float(rng.uniform(-180, 180))))
        elif k == 1:
            out.append(("arc", float(rng.uniform(200, 20000)), float(rng.uniform(-360, 360)), float(rng.uniform(10, 200))))
        elif k == 2:
            out.append(("rev", float(rng.uniform(10, 3000))))
        else:
            out.append(("line", float(rng.uniform(10, 200)), float(rng.uniform(-10, 10))))
    return out
