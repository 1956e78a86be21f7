"""PD with velocity and acceleration feedforward per axis, in integers:

    e = ref - pos,  de = e[k] - e[k-1]                      (D on the error, per tick)
    v = ref[k] - ref[k-W]                                   (the reference's speed over W ticks)
    a = ref[k] - 2 ref[k-W] + ref[k-2W]                     (its acceleration over W ticks)
    u = kp e + kd de + kv v + ka a + kf sign(v)             (clamped to +-duty_max)

Gains in physical units: kp_x, kp_y duty per count; kd_x, kd_y duty s per count; kv_x, kv_y duty per
(count/s); ka_x, ka_y duty per (count/s^2); optional kf_x, kf_y (friction feedforward, whole duty,
default 0) and win (W ticks, default 4). Formats: every gain Q8.8 after its tick scaling
(kd / T, kv / (W T), ka / (W T)^2), each term saturated (nnik.implementations.servo.fixed). A reset
takes the first tick's reference as the history (v = a = 0) and de = 0 on the first tick.
"""

from __future__ import annotations

from nnik.errors import NnikError
from nnik.implementations.servo import fixed as fx
from nnik.implementations.servo.base import FixedGains, check_duty_max, check_gains
from nnik.implementations.servo.window import RefHistory, check_window

NAMES = ("kp_x", "kd_x", "kv_x", "ka_x", "kp_y", "kd_y", "kv_y", "ka_y")
OPTIONAL = {"kf_x": 0, "kf_y": 0, "win": 4}


def _sign(v: int) -> int:
    return (v > 0) - (v < 0)


class Pdff(FixedGains):
    kind = "pdff"

    def __init__(self, gains: dict, tick_s: float, duty_max: int):
        g = check_gains(self.kind, gains, NAMES, OPTIONAL)
        self.gains, self.duty_max = g, check_duty_max(duty_max)
        w = check_window(g["win"])
        wt = w * tick_s
        q = {"NNIK_CTL_PDFF": 1, "NNIK_DUTY_MAX": duty_max, "NNIK_CTL_WIN": w, "NNIK_CTL_WIN_LOG2": w.bit_length() - 1}
        for a in ("x", "y"):
            A = a.upper()
            q[f"NNIK_KP_{A}"] = fx.quantise(f"kp_{a}", g[f"kp_{a}"], fx.Q_GAIN)
            q[f"NNIK_KD_{A}"] = fx.quantise(f"kd_{a}", g[f"kd_{a}"] / tick_s, fx.Q_GAIN)
            q[f"NNIK_KV_{A}"] = fx.quantise(f"kv_{a}", g[f"kv_{a}"] / wt, fx.Q_GAIN)
            q[f"NNIK_KA_{A}"] = fx.quantise(f"ka_{a}", g[f"ka_{a}"] / (wt * wt), fx.Q_GAIN)
            kf = g[f"kf_{a}"]
            if not (isinstance(kf, int) and 0 <= kf <= duty_max):
                raise NnikError(f"pdff gain kf_{a} must be a whole duty in 0 .. {duty_max}, not {kf!r}")
            q[f"NNIK_KF_{A}"] = kf
        self.q = q
        self.hist = (RefHistory(w), RefHistory(w))
        self.reset()

    def reset(self) -> None:
        for h in self.hist:
            h.reset()
        self.e_prev: list[int] | None = None

    def tick(self, ref, pos) -> tuple[int, int]:
        out = []
        e_now = [int(ref[i]) - int(pos[i]) for i in range(2)]
        for i, A in enumerate("XY"):
            r = int(ref[i])
            old1, old2 = self.hist[i].push(r)
            e = e_now[i]
            de = 0 if self.e_prev is None else fx.s16(e - self.e_prev[i])
            v = fx.s16(r - old1)
            acc = fx.s16(r - 2 * old1 + old2)
            q = self.q
            total = (fx.term(q[f"NNIK_KP_{A}"], fx.s16(e)) + fx.term(q[f"NNIK_KD_{A}"], de)
                     + fx.term(q[f"NNIK_KV_{A}"], v) + fx.term(q[f"NNIK_KA_{A}"], acc)
                     + _sign(v) * (q[f"NNIK_KF_{A}"] << fx.Q_OUT))
            out.append(fx.duty_out(total, self.duty_max))
        self.e_prev = e_now
        return tuple(out)

    def c_defines(self) -> dict[str, int]:
        return dict(self.q)
