"""A float reference of grbl 1.1's planner (grbl/planner.c), written from its documented rules, as
the oracle for the firmware's integer planner (codegen/arduino/src/nnik_plan.c, its Python twin
nnik.firmware.gcode.planner). It takes the interpreter's operations and the same limits
(MachineConfig: per-axis acceleration, junction deviation, max feed, queue length):

* a block is a push to a new point (a zero-length push is dropped, as the firmware drops it);
  its length L and unit vector u are exact (float) from the integer end points;
* nominal speed vn = min(F, max feed) / 60 (um/s);
* block acceleration a = min over the moving axes of a_axis / |u_axis| (grbl's
  limit_value_by_axis_maximum), so no axis exceeds its own limit along the block;
* with motor limits (MachineConfig.motor_rows), vn and a also at most each motor's limit along u
  (motor_limit: grbl's rule on the motor axes, the same rows as the firmware's);
* junction (grbl's junction deviation): cos_theta = -(u_prev . u); above 0.999999 (a reversal)
  the junction speed is 0 (MINIMUM_JUNCTION_SPEED); below -0.999999 (straight on) it is
  unlimited; else with the junction unit vector w = (u - u_prev) / |u - u_prev|, its
  acceleration a_j = min over axes of a_axis / |w_axis| and sin(theta/2) = sqrt((1 - cos_theta)/2),
      v_j^2 = a_j * delta * sin(theta/2) / (1 - sin(theta/2)),
  and the block's max entry speed is min(v_j, vn_prev, vn) (0 for the first block after rest);
* backward pass: the last planned block ends at rest; going back, exit_k = min(max entry of
  k+1, sqrt(exit_{k+1}^2 + 2 a_{k+1} L_{k+1}));
* forward pass: each block starts at the speed the block before ended with, and its exit is at
  most sqrt(entry^2 + 2 a L); a block runs the trapezoid (or triangle) between them at a;
* lookahead: with N blocks (MachineConfig.plan_blocks, the firmware's queue) the block being
  executed is planned with the N - 1 blocks queued behind it, the last of them ending at rest
  (the firmware samples its head block only when the queue is full, so this is exactly its
  lookahead); lookahead=None plans to the next stop (unlimited);
* a flush (M400, a dwell, a tool change, the end) ends the motion at rest: no junction across it;
* an arc operation (nnik.firmware.gcode.planner_arc) is one block: its length the sum of its
  chords' exact lengths, entry and exit along its first and last chord, acceleration
  amin / sqrt(2) (amin the least axis limit), nominal speed min(F, sqrt(amin r / sqrt(2)), grbl's
  junction limit at every vertex between its chords): the arc's centripetal limit, and no vertex
  inside passed faster than grbl's rule allows there.

Speeds are um/s, accelerations um/s^2, times s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

COS_REVERSAL = 0.999999  # grbl: junction_cos_theta above this is a reversal (speed 0)
COS_STRAIGHT = -0.999999  # below this the junction is straight on (no limit)


@dataclass
class FBlock:
    index: int  # the push's index (op[5])
    length: float  # um
    u: tuple[float, float]
    vn: float  # um/s
    acc: float  # um/s^2
    entry_max: float = 0.0  # the junction limit with the block before (0: from rest)
    u_out: tuple[float, float] | None = None  # an arc's last chord's direction (None: u)
    cap: float = math.inf  # an arc's speed limit, the feed's aside: centripetal and its vertices'


@dataclass
class FPlan:
    """The float planner's result over a job: its blocks (in stops-separated runs), each block's
    planned entry and exit speed and time, and the whole motion time."""

    runs: list[list[FBlock]]
    entry: dict[int, float]  # push index -> entry speed (um/s)
    exit: dict[int, float]
    time_s: float


def axis_limit(limits: tuple[float, float], u: tuple[float, float]) -> float:
    """grbl's limit_value_by_axis_maximum: the largest value along u that keeps every axis
    within its own limit."""
    return min((lim / abs(c) for lim, c in zip(limits, u) if c != 0.0), default=math.inf)


def junction_limit(u0, u1, vn0: float, vn1: float, accel: tuple[float, float], dev_um: float) -> float:
    """grbl 1.1's max entry speed of the block with direction u1 after one with u0 (um/s)."""
    cos_theta = -(u0[0] * u1[0] + u0[1] * u1[1])
    cap = min(vn0, vn1)
    if cos_theta > COS_REVERSAL:
        return 0.0
    if cos_theta < COS_STRAIGHT:
        return cap
    w = (u1[0] - u0[0], u1[1] - u0[1])
    n = math.hypot(*w)
    a_j = axis_limit(accel, (w[0] / n, w[1] / n))
    s = math.sqrt(0.5 * (1.0 - cos_theta))
    return min(cap, math.sqrt(a_j * dev_um * s / (1.0 - s)))


def motor_limit(cfg, u: tuple[float, float]) -> tuple[float, float]:
    """The motor limits after the IK along u (cfg.motor_rows, nnik.machine.motor_limits): the
    largest speed (um/s) and acceleration (um/s^2) with every motor within its own, per motor
    V / (|c . u| + d) and A / (|c . u| + d) (the rows in Q15), and the speed at most vc."""
    v = a = math.inf
    for cx, cy, d, vm, am in getattr(cfg, "motor_rows", ()):
        n = (abs(cx * u[0] + cy * u[1]) + d) / 32768.0
        if n > 0:
            v = min(v, vm / n) if vm else v
            a = min(a, am / n) if am else a
    vc = getattr(cfg, "motor_vc_um_s", 0)
    return (min(v, vc) if vc else v), a


def blocks_of(ops: list[tuple], cfg) -> list[list[FBlock]]:
    """The pushes as float blocks, in runs that end at rest (a flush or rest op ends a run)."""
    accel = tuple(float(a) for a in cfg.accel_um_s2)
    runs, cur, last = [], [], (0, 0)
    for op in ops:
        if op[0] not in ("push", "arc"):
            if cur:
                runs.append(cur)
            cur = []
            continue
        vn = min(op[3], cfg.max_feed_um_min) / 60.0
        if op[0] == "arc":  # arc blocks are a study of the model (no motor limits with them)
            b = arc_block(last, op, vn, accel, float(cfg.junction_dev_um))
        else:
            dx, dy = op[1] - last[0], op[2] - last[1]
            if not dx and not dy:
                continue
            L = math.hypot(dx, dy)
            u = (dx / L, dy / L)
            mv, ma = motor_limit(cfg, u)
            b = FBlock(op[5], L, u, min(vn, mv), min(axis_limit(accel, u), ma))
        if cur:
            p = cur[-1]
            b.entry_max = junction_limit(p.u if p.u_out is None else p.u_out, b.u, p.vn, b.vn, accel,
                                         float(cfg.junction_dev_um))
        cur.append(b)
        last = (op[1], op[2])
    if cur:
        runs.append(cur)
    return runs


def arc_block(last, op: tuple, vn: float, accel: tuple[float, float], dev_um: float) -> FBlock:
    """The float block of an ("arc", x, y, feed, tool, index, points, r) operation."""
    us, L, p = [], 0.0, last
    for q in op[6]:
        dx, dy = q[0] - p[0], q[1] - p[1]
        if dx or dy:
            n = math.hypot(dx, dy)
            us.append((dx / n, dy / n))
            L += n
            p = q
    a = min(accel) / math.sqrt(2.0)
    cap = math.sqrt(a * op[7])
    for k in range(1, len(us)):
        cap = min(cap, junction_limit(us[k - 1], us[k], math.inf, math.inf, accel, dev_um))
    return FBlock(op[5], L, us[0], min(vn, cap), a, u_out=us[-1], cap=cap)


def block_time(L: float, v0: float, v1: float, vn: float, a: float) -> float:
    """Time of a trapezoid (or triangle) from v0 to v1 over L at acceleration a, cruising at vn."""
    vp2 = (2.0 * a * L + v0 * v0 + v1 * v1) / 2.0
    if vp2 <= vn * vn:
        vp = math.sqrt(vp2)
        return (2.0 * vp - v0 - v1) / a
    up, down = (vn * vn - v0 * v0) / (2.0 * a), (vn * vn - v1 * v1) / (2.0 * a)
    return (vn - v0) / a + (vn - v1) / a + (L - up - down) / vn


def plan(ops: list[tuple], cfg, lookahead: int | None = -1) -> FPlan:
    """Plan the job: lookahead -1 (default) uses cfg.plan_blocks, None is unlimited, else that
    many blocks (the executing one included)."""
    n = cfg.lookahead if lookahead == -1 else lookahead
    runs = blocks_of(ops, cfg)
    entry, exit_, total = {}, {}, 0.0
    for run in runs:
        m = len(run)
        # backward limits: lim[k] = the most block k may exit with, given blocks k+1..end at rest
        def backward(i: int, end: int) -> float:
            e = 0.0
            for k in range(end - 1, i, -1):
                b = run[k]
                e = min(b.entry_max, math.sqrt(e * e + 2.0 * b.acc * b.length))
            return e

        full = None
        if n is None:  # one pass serves every block
            full, e = [0.0] * m, 0.0
            for k in range(m - 1, 0, -1):
                e = min(run[k].entry_max, math.sqrt(e * e + 2.0 * run[k].acc * run[k].length))
                full[k - 1] = e
        v = 0.0
        for i, b in enumerate(run):
            planned = full[i] if full is not None else backward(i, min(m, i + n))
            ex = min(planned, math.sqrt(v * v + 2.0 * b.acc * b.length))
            entry[b.index], exit_[b.index] = v, ex
            total += block_time(b.length, v, ex, b.vn, b.acc)
            v = ex
    return FPlan(runs, entry, exit_, total)
