"""The arcs and curves of a line, checked before the line changes anything (the interpreter's
part that nnik_gcode.c does in nnik_gc_exec before committing): grbl's arc checks, the centre of an
R arc, every plane's chord ends, Marlin's G5, and the exact XY path the contour is measured to."""

from __future__ import annotations

from math import isqrt

from nnik.firmware.gcode.codes import GcodeLineError
from nnik.firmware.gcode.geometry import arc_points, bezier_points, r_centre
from nnik.firmware.gcode.program import POS_LIMIT

PLANES = ((0, 1), (2, 0), (1, 2))  # G17 XY, G18 ZX, G19 YZ: grbl's (axis_0, axis_1)
OFFSET_LETTERS = "IJK"


def arc(it, v, tgt, plane: int, inch: bool, arc_abs: bool, wcs: int, tlo: int, ccw: bool, used: set):
    """An arc's centre, radius and chord ends (G2/G3 in any plane), checked as grbl checks them."""
    a0, a1 = PLANES[plane]
    lin = 3 - a0 - a1
    names = "XYZ"
    if names[a0] not in v and names[a1] not in v:
        raise GcodeLineError(32)
    if plane and tgt[lin] != it.mp[lin]:
        raise GcodeLineError(20, "a helix outside G17")
    x, y = tgt[a0] - it.mp[a0], tgt[a1] - it.mp[a1]
    if "R" in v:
        used.add("R")
        rad = v["R"].to_um(inch)
        if rad == 0:
            raise GcodeLineError(33, "R0")
        off = r_centre(x, y, rad, ccw)
    else:
        o0, o1 = OFFSET_LETTERS[a0], OFFSET_LETTERS[a1]
        if o0 not in v and o1 not in v:
            raise GcodeLineError(35)
        used |= {o0, o1}
        off = [v[o].to_um(inch) if o in v else 0 for o in (o0, o1)]
        if arc_abs:
            off = [off[0] + it.wco(a0, wcs, tlo) - it.mp[a0], off[1] + it.wco(a1, wcs, tlo) - it.mp[a1]]
    c = (it.mp[a0] + off[0], it.mp[a1] + off[1])
    if abs(c[0]) > POS_LIMIT or abs(c[1]) > POS_LIMIT:
        raise GcodeLineError(33, "the centre is out of range")
    cur = (it.mp[a0] - c[0], it.mp[a1] - c[1])
    e = (tgt[a0] - c[0], tgt[a1] - c[1])
    r = isqrt(cur[0] ** 2 + cur[1] ** 2)
    if r == 0:
        raise GcodeLineError(33, "radius zero")
    re = isqrt(e[0] ** 2 + e[1] ** 2)
    if re == 0 or abs(re - r) > 5 + r // 1000:
        raise GcodeLineError(33, "the end is off the circle")
    pts = arc_points(cur, e, r, ccw, it.cfg.seg_um)
    out = []
    for q in pts:
        p = list(tgt)
        p[a0], p[a1] = c[0] + q[0], c[1] + q[1]
        out.append(tuple(p))
    if plane == 0:
        return "arc2d", out, (c, r, ccw)
    return "arc3d", out, _projected_arc(it.mp, tgt, a0, a1, c, r, ccw)

def bezier(it, v, tgt, inch: bool, used: set):
    """Marlin's G5: control points and chord ends."""
    if "P" not in v or "Q" not in v:
        raise GcodeLineError(28, "G5 needs P and Q")
    used |= {"I", "J", "P", "Q"}
    p0 = (it.mp[0], it.mp[1])
    if "I" in v or "J" in v:
        c1 = (p0[0] + (v["I"].to_um(inch) if "I" in v else 0), p0[1] + (v["J"].to_um(inch) if "J" in v else 0))
    elif it.motion == 5 and it.bezier_c2 is not None:
        c1 = (2 * p0[0] - it.bezier_c2[0], 2 * p0[1] - it.bezier_c2[1])
    else:
        raise GcodeLineError(28, "G5 needs I and J (no G5 before to continue)")
    p3 = (tgt[0], tgt[1])
    c2 = (p3[0] + v["P"].to_um(inch), p3[1] + v["Q"].to_um(inch))
    if any(abs(q) > POS_LIMIT for q in (*c1, *c2)):
        raise GcodeLineError(33, "a control point out of range")
    pts = [(q[0], q[1], tgt[2]) for q in bezier_points(p0, c1, c2, p3, it.cfg.seg_um)]
    exact = [_bez(p0, c1, c2, p3, k / 64) for k in range(65)]
    return "curve", pts, exact, c2


def _bez(p0, p1, p2, p3, t: float) -> tuple[float, float]:
    u = 1 - t
    return tuple(u ** 3 * p0[a] + 3 * u * u * t * p1[a] + 3 * u * t * t * p2[a] + t ** 3 * p3[a] for a in range(2))


def _projected_arc(mp, tgt, a0, a1, c, r, ccw) -> list[tuple[float, float]]:
    """The exact XY path of an arc in G18/G19 (a line in XY, traced back and forth)."""
    from math import atan2, cos, pi, sin

    t0 = atan2(mp[a1] - c[1], mp[a0] - c[0])
    t1 = atan2(tgt[a1] - c[1], tgt[a0] - c[0])
    sweep = (t1 - t0) % (2 * pi) if ccw else -((t0 - t1) % (2 * pi))
    if sweep == 0:
        sweep = 2 * pi if ccw else -2 * pi
    out = []
    for k in range(129):
        t = t0 + sweep * k / 128
        p = list(map(float, mp))
        p[a0], p[a1] = c[0] + r * cos(t), c[1] + r * sin(t)
        out.append((p[0], p[1]))
    return out
