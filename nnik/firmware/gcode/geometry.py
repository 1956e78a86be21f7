"""Arc and Bezier chords in integers, as nnik_gcode.c cuts them (every rounding spelled out).

Arcs: quarter turns, each bisected until every chord is <= seg_um; a midpoint is (a + b) scaled
to the radius, rounded half away from zero. Bezier (Marlin's G5): n equal steps of t, n the
control polygon's length over seg_um rounded up (1..NMAX), each point p0 + the exact cubic's offset
from p0 at k / n, rounded half away from zero.
"""

from __future__ import annotations

from math import isqrt

from nnik.firmware.gcode.codes import GcodeLineError

ARC_STACK = 16  # bisections: chords of 100 um from any piece shorter than 6.5 m (nnik_gc_geom.h)
BEZIER_NMAX = 1024


def div_round(a: int, b: int) -> int:
    """round(a / b) half away from zero, b > 0."""
    q = (2 * abs(a) + b) // (2 * b)
    return -q if a < 0 else q


def r_centre(x: int, y: int, rad: int, ccw: bool) -> tuple[int, int]:
    """The centre of an R-form arc as an offset from its start, for the chord (x, y) and the
    radius rad (not zero; negative: the long way round), as r_centre() in nnik_gcode.c:
    (x, y) / 2 + sign * (-y, x) * s / (2 d), s = floor(sqrt(4 rad^2 - d^2)) (0 when the chord
    is longer than 2|rad| by at most the end tolerance), d = |(x, y)| taken as floor(d * 2^k) / 2^k
    with 2^29 <= d * 2^k < 2^30; the centre lies left of the chord for G3 and a positive R."""
    d2 = x * x + y * y
    if d2 == 0:
        raise GcodeLineError(33, "an R arc that ends at its start")
    ra = abs(rad)
    s = 0
    if 4 * ra * ra < d2:
        if isqrt(d2) > 2 * ra + 5 + ra // 1000:
            raise GcodeLineError(33, "an R arc whose chord is longer than 2|R|")
    else:
        s = isqrt(4 * ra * ra - d2)
    k, d2s = 0, d2
    while d2s < 1 << 58:
        d2s <<= 2
        k += 1
    ds = isqrt(d2s)
    sign = 1 if ccw == (rad > 0) else -1
    return (div_round(x * ds - sign * (y << k) * s, 2 * ds), div_round(y * ds + sign * (x << k) * s, 2 * ds))


def _piece(cur, end, r: int, seg2: int, out: list) -> tuple[int, int]:
    stack = [end]
    while stack:
        b = stack[-1]
        if (b[0] - cur[0]) ** 2 + (b[1] - cur[1]) ** 2 <= seg2 or len(stack) == ARC_STACK:
            cur = b
            stack.pop()
            out.append(cur)
        else:
            mx, my = cur[0] + b[0], cur[1] + b[1]
            m = isqrt(mx * mx + my * my)
            stack.append((div_round(mx * r, m), div_round(my * r, m)))
    return cur


def arc_points(cur: tuple[int, int], e: tuple[int, int], r: int, ccw: bool, seg_um: int) -> list[tuple[int, int]]:
    """The chord ends (offsets from the centre) of the arc from cur to e, radius r: quarter
    turns while the end is not within the next one (a full circle when e == cur)."""
    out: list[tuple[int, int]] = []
    seg2 = seg_um * seg_um
    while True:
        cross = cur[0] * e[1] - cur[1] * e[0]
        dot = cur[0] * e[0] + cur[1] * e[1]
        if not ccw:
            cross = -cross
        if cross > 0 and dot >= 0:
            _piece(cur, e, r, seg2, out)
            return out
        nxt = (-cur[1], cur[0]) if ccw else (cur[1], -cur[0])
        cur = _piece(cur, nxt, r, seg2, out)


def chord_length(points: list[tuple[int, int]], start: tuple[int, int]) -> int:
    """Sum of floor chord lengths along the points from start (G93's arc length)."""
    total, p = 0, start
    for q in points:
        total += isqrt((q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2)
        p = q
    return total


def bezier_points(p0, p1, p2, p3, seg_um: int) -> list[tuple[int, int]]:
    """Points of the cubic p0 p1 p2 p3 at t = k / n, k = 1..n."""
    poly = sum(isqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2) for a, b in ((p0, p1), (p1, p2), (p2, p3)))
    n = min(max((poly + seg_um - 1) // seg_um, 1), BEZIER_NMAX)
    n3 = n * n * n
    out = []
    for k in range(1, n + 1):
        u = n - k
        w1, w2, w3 = 3 * u * u * k, 3 * u * k * k, k * k * k
        out.append(tuple(p0[a] + div_round(w1 * (p1[a] - p0[a]) + w2 * (p2[a] - p0[a]) + w3 * (p3[a] - p0[a]), n3)
                         for a in range(2)))
    return out
