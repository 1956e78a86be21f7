"""Koren's cross-coupled controller (ASME JDSMC 102(4), 1980) in integers: the Arduino-library PID
per axis (pid.py) plus a PD on the contour error, fed back to both axes along the path's normal.

    (dx, dy) = ref[k] - ref[k-W]                  the path's direction over W ticks (window.py)
    (sin, cos) = (dy, dx) * 16 / isqrt(256 (dx^2 + dy^2))   Q14, one division, no trigonometry (the
                                                  16x finer root keeps |(sin, cos)| within 1/(16 L) of 1);
                                                  dx, dy saturated to +-2047 counts; held while the
                                                  reference moved less than min_chord counts
    eps = -e_x sin + e_y cos                      the contour error (Koren's straight-line formula), Q4 counts
    uc  = kcp eps + kcd (eps[k] - eps[k-1])       Q8 duty, saturated to +-384 duty
    u_x = PID_x - sin uc,  u_y = PID_y + cos uc   each clamped to +-duty_max

The straight-line formula is used on every path: on a circle of radius R it estimates the contour
error to within |e|^2 / (2 R) (a 0.1 mm error on a 20 mm circle: 0.25 um), far below a count, so
Koren's later curvature-dependent gains are not needed at these radii. Before the reference has
moved, sin = cos = 0: no contour correction.

Gains: the PID's kp_x ... kd_y (pid.py's units) and kcp (duty per count), kcd (duty s per count);
optional win (W ticks, default 4) and min_chord (counts over the window, default 2).
"""

from __future__ import annotations

from math import isqrt

from nnik.errors import NnikError
from nnik.implementations.servo import fixed as fx
from nnik.implementations.servo.base import FixedGains, check_duty_max, check_gains
from nnik.implementations.servo.pid import NAMES as PID_NAMES
from nnik.implementations.servo.pid import pid_axes, pid_gains_q
from nnik.implementations.servo.window import RefHistory, check_window

NAMES = (*PID_NAMES, "kcp", "kcd")
OPTIONAL = {"win": 4, "min_chord": 2}
Q_DIR = 14
CHORD_MAX = 2047  # the chord's components saturate here (5 mm over the window): l2 << 8 fits 32 bits
UC_MAX = 3 << 15  # the correction's saturation, Q8 duty (384 duty): sin * uc stays inside int32 (|sin| <= 17,408)


class Ccc(FixedGains):
    kind = "ccc"

    def __init__(self, gains: dict, tick_s: float, duty_max: int):
        g = check_gains(self.kind, gains, NAMES, OPTIONAL)
        self.gains, self.duty_max = g, check_duty_max(duty_max)
        w = check_window(g["win"])
        mc = g["min_chord"]
        if not (isinstance(mc, int) and 1 <= mc <= 1000):
            raise NnikError(f"ccc min_chord must be a whole number of counts in 1 .. 1000, not {mc!r}")
        self.q = {"NNIK_CTL_CCC": 1, "NNIK_DUTY_MAX": duty_max, **pid_gains_q(g, tick_s),
                  "NNIK_KCP": fx.quantise("kcp", g["kcp"], fx.Q_GAIN),
                  "NNIK_KCD": fx.quantise("kcd", g["kcd"] / tick_s, fx.Q_GAIN),
                  "NNIK_CTL_WIN": w, "NNIK_CTL_WIN_LOG2": w.bit_length() - 1, "NNIK_CCC_MIN_CHORD": mc}
        self.axes = pid_axes(self.q, duty_max)
        self.hist = (RefHistory(w), RefHistory(w))
        self.reset()

    def reset(self) -> None:
        for ax in self.axes:
            ax.reset()
        for h in self.hist:
            h.reset()
        self.sin = self.cos = 0
        self.eps_prev: int | None = None

    def _direction(self, ref) -> None:
        dx, dy = (fx.sat(int(ref[i]) - self.hist[i].push(int(ref[i]))[0], CHORD_MAX) for i in range(2))
        l2 = dx * dx + dy * dy
        mc = self.q["NNIK_CCC_MIN_CHORD"]
        if l2 >= mc * mc:
            inv = (1 << 28) // isqrt(l2 << 8)
            self.sin = (dy * inv + (1 << 9)) >> 10
            self.cos = (dx * inv + (1 << 9)) >> 10

    def tick(self, ref, pos) -> tuple[int, int]:
        acc = [ax.acc_q8(int(ref[i]), int(pos[i])) for i, ax in enumerate(self.axes)]
        self._direction(ref)
        ex, ey = (fx.s16(int(ref[i]) - int(pos[i])) for i in range(2))
        eps = fx.s16((-ex * self.sin + ey * self.cos) >> (Q_DIR - 4))
        deps = 0 if self.eps_prev is None else fx.s16(eps - self.eps_prev)
        self.eps_prev = eps
        uc = fx.sat((fx.term(self.q["NNIK_KCP"], eps) + fx.term(self.q["NNIK_KCD"], deps)) >> 4, UC_MAX)
        return (fx.duty_out(acc[0] + ((-self.sin * uc) >> Q_DIR), self.duty_max),
                fx.duty_out(acc[1] + ((self.cos * uc) >> Q_DIR), self.duty_max))

    def c_defines(self) -> dict[str, int]:
        return dict(self.q)
