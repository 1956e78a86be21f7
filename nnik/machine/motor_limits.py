"""Motor limits after the IK: [motion] motor_max_speed and motor_max_accel (issue 26 item 1).

Units are the motor's own, as a user of each family types them: microsteps/s and microsteps/s^2
for steppers (the step rate grbl and Klipper users know: steps/mm x mm/s), mirror (mechanical)
degrees/s and degrees/s^2 for galvos, encoder counts/s and counts/s^2 for DC servos.  A number
holds for both motors, [m1, m2] for each.

The planner runs on the head's path, so each motor limit becomes a bound on the head (Python
decides, the C executes: nnik_plan.c motor_caps, its twin nnik.firmware.gcode.planner.motor_caps).
With J_i(p) motor i's Jacobian row (rad per mm) and J0_i its value at the workspace's centre:

    |dq_i/dt|   = |J_i(p) . u| v                  <= (|J0_i . u| + delta_i) v
    |d2q_i/dt2| <= |J_i(p) . u| a + |u' H_i u| v^2 <= (|J0_i . u| + delta_i) a + K_i v^2

on a straight block (direction u, speed v, acceleration a along u), delta_i = max_p |J_i(p) - J0_i|
and K_i = max_p ||H_i(p)|| (the Hessian's spectral norm) over the workspace.  So each block's vn
and acc are capped per direction at V_i / (|J0_i . u| + delta_i) and (A_i - K_i vmax^2) /
(|J0_i . u| + delta_i): on a linear machine (CoreXY, HBOT, an XY table without distortion)
delta = K = 0 and this is grbl's per-axis rule on the motor axes, exact; on a nonlinear one
(galvo, a distorted CoreXY) it is a constant margin, and when K_i vfeed^2 would take more than
half of A_i the head's speed is capped at vmax = sqrt(A_i / (2 K_i)) (vc below).  delta and K
are sampled on a GRID x GRID grid with central differences; delta gets K times the grid cell's
half diagonal (J moves at most that between grid points) and K the margin K_MARGIN.
"""

from __future__ import annotations

import math

import numpy as np

from nnik.errors import NnikError
from nnik.machine import ranges
from nnik.machine.params import Param

# the [motion] keys, parsed and checked here (a number or [m1, m2], in the motor's units)
PARAMS = {
    "motor_max_speed": Param("pair", doc="each motor's top speed after the IK, its units per s"),
    "motor_max_accel": Param("pair", doc="each motor's top acceleration after the IK, its units per s^2"),
}
KEYS = tuple(PARAMS)
UNITS = {"stepper": "microsteps", "dac": "mirror degrees", "dc_servo": "encoder counts"}
GRID = 41
K_MARGIN = 1.1
LINEAR_REL = 1e-7  # delta and K below this (relative to |J0|) are numerical noise: a linear map


def _to_rad(actuator, value: float) -> float:
    """A motor limit in the user's unit (per s or per s^2) as joint radians."""
    if actuator.kind == "dac":
        return math.radians(value)
    return value / actuator.units_per_rad


def jacobian_bounds(mechanism, workspace) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(J0 (2, 2) rad/mm, delta (2,), K (2,)) over the workspace, as the module states."""
    span = np.maximum(workspace.hi - workspace.lo, 1e-9)
    h = 1e-4 * span
    pts = workspace.grid(GRID)

    def jac(p):
        cols = [(mechanism.inverse(p + h[j] * e) - mechanism.inverse(p - h[j] * e)) / (2 * h[j])
                for j, e in enumerate(np.eye(2))]
        return np.stack(cols, 2)  # (N, motor, axis)

    J = jac(pts)
    J0 = jac(workspace.center[None, :])[0]
    hd = 1e-3 * span
    H = np.stack([(jac(pts + hd[j] * e) - jac(pts - hd[j] * e)) / (2 * hd[j]) for j, e in enumerate(np.eye(2))], 3)
    scale = np.abs(J0).max(axis=1)
    K = np.array([np.linalg.norm(H[:, i], ord=2, axis=(1, 2)).max() for i in range(2)])
    delta = np.linalg.norm(J - J0[None], axis=2).max(axis=0)
    linear = (K < LINEAR_REL * scale) & (delta < LINEAR_REL * scale)
    K = np.where(linear, 0.0, K * K_MARGIN)
    cell = float(np.hypot(*(span / (GRID - 1)))) / 2
    delta = np.where(linear, 0.0, delta + K * cell)
    return J0, delta, K


def _limits(motion: dict, key: str, actuator) -> tuple[float, float] | None:
    v = motion.get(key)
    return None if v is None else tuple(_to_rad(actuator, float(x)) for x in v)


def motor_rows(mechanism, actuator, workspace, motion: dict, source: str = "<scenario>") -> tuple[tuple, int]:
    """((cx, cy, d, v_um_s, a_um_s2) per motor, vc_um_s) for nnik.firmware.config.MachineConfig:
    Q15 coefficients of the row (J0_i + delta_i) normalised by s_i = max |J0_i| + delta_i, the
    head-equivalent bounds 1000 V_i / s_i and 1000 (A_i - K_i vmax^2) / s_i (0: none) and the
    head's speed cap vc (0: none), all floor (conservative); ((), 0) without motor limits.
    Bad values: NnikError."""
    speed, accel = (_limits(motion, k, actuator) for k in KEYS)
    if speed is None and accel is None:
        return (), 0
    where = f"[motion] {KEYS[1] if accel is not None else KEYS[0]}"
    if not mechanism.analytic:
        raise NnikError("motor limits need the exact IK (a measured mechanism has none)", source, where)
    J0, delta, K = jacobian_bounds(mechanism, workspace)
    vfeed = motion["max_feed_mm_min"] / 60.0  # mm/s
    vmax = vfeed
    if accel is not None:
        for i in range(2):
            if K[i] * vfeed * vfeed > accel[i] / 2:
                vmax = min(vmax, math.sqrt(accel[i] / (2 * K[i])))
    vc = max(int(vmax * 1000), 1) if vmax < vfeed else 0  # 1 at least: 0 means none
    rows = []
    for i in range(2):
        s = float(np.abs(J0[i]).max() + delta[i])
        c = [int(round(x / s * ranges.MOTOR_Q15)) for x in J0[i]]
        exact = all(x / s * ranges.MOTOR_Q15 == ci for x, ci in zip(J0[i], c))
        d = math.ceil(delta[i] / s * ranges.MOTOR_Q15) + (0 if exact else 1)
        v = max(int(1000 * speed[i] / s), 1) if speed is not None else 0
        a = max(int(1000 * (accel[i] - K[i] * vmax * vmax) / s), 1) if accel is not None else 0
        problem = ranges.motor_problem(v, a, motion["sample_hz"]) or ranges.motor_problem(vc, 0, motion["sample_hz"])
        if problem:
            raise NnikError(f"motor {i + 1} {problem}", source, where)
        rows.append((c[0], c[1], d, v, a))
    return tuple(rows), vc


def parse_keys(raw: dict, source: str) -> dict:
    """The motor keys of a [motion] table as (m1, m2) floats (None: absent). Bad values: NnikError."""
    out = {}
    for key, (lo, hi) in zip(KEYS, (ranges.MOTOR_SPEED_RANGE, ranges.MOTOR_ACCEL_RANGE)):
        value = raw.get(key)
        if value is None:
            out[key] = None
            continue
        vals = value if isinstance(value, list) else [value]
        vals = vals * 2 if len(vals) == 1 else vals
        if len(vals) != 2 or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in vals):
            raise NnikError(f"expected a number or [motor1, motor2], got {value!r}", source, f"[motion] {key}")
        for v in vals:
            if not (math.isfinite(v) and lo <= v <= hi):
                raise NnikError(f"must be in [{lo:g}, {hi:g}] (the motor's units per s{'^2' if 'accel' in key else ''}), "
                                f"got {v!r}", source, f"[motion] {key}")
        out[key] = (float(vals[0]), float(vals[1]))
    return out
