"""A PID per axis in integer arithmetic with the Arduino PID library's semantics (br3ttb v1.2.1,
Compute() with P on error):

    e       = ref - pos
    dInput  = pos - lastPos                   (derivative on measurement: no kick on a step)
    I       = clamp(I + ki * e, -duty_max, duty_max)        (anti-windup: the integral is clamped)
    u       = clamp(kp * e + I - kd * dInput, -duty_max, duty_max)
    lastPos = pos

with the library's per-tick gains: ki = Ki * T, kd = Kd / T (SetTunings). As the library's
Initialize() on the switch to automatic, a reset zeroes I (the output was 0) and the first tick takes
lastPos = pos.

Gains, in the library's units: kp_x, kp_y (duty per count), ki_x, ki_y (duty per count per second),
kd_x, kd_y (duty seconds per count). Formats (nnik.implementations.servo.fixed): kp and kd/T in
Q8.8, ki T in Q0.16; I in Q16 duty, clamped to +-duty_max << 16; e and dInput saturated to int16.
"""

from __future__ import annotations

from nnik.implementations.servo import fixed as fx
from nnik.implementations.servo.base import FixedGains, check_duty_max, check_gains

NAMES = ("kp_x", "ki_x", "kd_x", "kp_y", "ki_y", "kd_y")


class PidAxis:
    """One axis' PID state and its Q8 output before rounding (the CCC adds to it)."""

    def __init__(self, kp_q: int, ki_q: int, kd_q: int, duty_max: int):
        self.kp_q, self.ki_q, self.kd_q = kp_q, ki_q, kd_q
        self.i_max = duty_max << fx.Q_INT
        self.reset()

    def reset(self) -> None:
        self.integral = 0
        self.last = None

    def acc_q8(self, ref: int, pos: int) -> int:
        e = fx.s16(ref - pos)
        d_in = 0 if self.last is None else fx.s16(pos - self.last)
        self.last = pos
        self.integral = fx.sat(self.integral + fx.sat(self.ki_q * e, 2 * self.i_max), self.i_max)
        return fx.term(self.kp_q, e) + (self.integral >> (fx.Q_INT - fx.Q_OUT)) - fx.term(self.kd_q, d_in)


def pid_gains_q(gains: dict, tick_s: float) -> dict[str, int]:
    """The quantised gains as the C macros NNIK_KP_X ... (kp Q8.8, ki T Q0.16, kd / T Q8.8)."""
    out = {}
    for a in ("x", "y"):
        out[f"NNIK_KP_{a.upper()}"] = fx.quantise(f"kp_{a}", gains[f"kp_{a}"], fx.Q_GAIN)
        out[f"NNIK_KI_{a.upper()}"] = fx.quantise(f"ki_{a}", gains[f"ki_{a}"] * tick_s, fx.Q_INT)
        out[f"NNIK_KD_{a.upper()}"] = fx.quantise(f"kd_{a}", gains[f"kd_{a}"] / tick_s, fx.Q_GAIN)
    return out


def pid_axes(q: dict[str, int], duty_max: int) -> tuple[PidAxis, PidAxis]:
    return tuple(PidAxis(q[f"NNIK_KP_{a}"], q[f"NNIK_KI_{a}"], q[f"NNIK_KD_{a}"], duty_max) for a in "XY")


class Pid(FixedGains):
    kind = "pid"

    def __init__(self, gains: dict, tick_s: float, duty_max: int):
        self.gains = check_gains(self.kind, gains, NAMES, {})
        self.duty_max = check_duty_max(duty_max)
        self.q = pid_gains_q(self.gains, tick_s)
        self.axes = pid_axes(self.q, duty_max)

    def reset(self) -> None:
        for ax in self.axes:
            ax.reset()

    def tick(self, ref, pos) -> tuple[int, int]:
        return tuple(fx.duty_out(ax.acc_q8(int(ref[i]), int(pos[i])), self.duty_max)
                     for i, ax in enumerate(self.axes))

    def c_defines(self) -> dict[str, int]:
        return {"NNIK_CTL_PID": 1, "NNIK_DUTY_MAX": self.duty_max, **self.q}
