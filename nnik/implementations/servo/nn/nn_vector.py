"""nn_vector: the vectorial neural controller, one online-learning 4-8-1 network in polar form
(issue 29, item 2; formats: formats.py).

    e = R - V per axis (counts, saturated to int16), m = |e| = isqrt(ex^2 + ey^2) (<= 46,340)
    x = (m[k], m[k] - m[k-1], m[k] - 2 m[k-1] + m[k-2], |R|)
    |R| = max(|a|, |b|) + (3 min(|a|, |b|)) >> 3 with a, b = sat16(rx >> r_shift), sat16(ry >> r_shift):
    the reference's distance from the workspace origin in units of 2^r_shift counts, by the
    octagonal estimate (at most 6.8 % above the Euclidean distance, never below it, no square root:
    it saves the chip a second isqrt). It plays the bias's part.
    U = duty_out(y >> out_shift)                          the net's output, a duty

The split of U into Ux, Uy is OUR RECONSTRUCTION of the seed's lost eqs. 25-26: U along the
error's direction, the weaker axis (smaller Jacobian) getting proportionally more:
    Ux = U (ex / m) c_x,   Uy = U (ey / m) c_y,   c_a = J_max / J_a (>= 1, at most 16)
in integers: the unit vector in Q14 from one division, inv = 2^30 // m, u_a = (e_a inv + 2^15) >> 16
(|e_a| <= m, so |e_a inv| <= 2^30: one 32 x 16 product per axis); c_a in Q8 (uint16, rounded);
t_a = (U u_a + 2^10) >> 11 (Q3 duty, int16 for any duty_max <= 4095); duty_a = duty_out((t_a c_a) >> 3).
m = 0 gives no direction: both duties 0.

Learning uses only the Jacobian's sign (both Jacobians are > 0): delta_out = x_0 = scaled |e|[k]
>= 0 (a larger U along e shrinks |e|). Anti-windup as net.py, on U.
"""

from __future__ import annotations

from math import isqrt

from nnik.errors import NnikError
from nnik.implementations.servo import fixed as fx
from nnik.implementations.servo.nn import formats as f
from nnik.implementations.servo.nn.controller import NeuralController

Q_DIR = 14
C_MAX = 16 << 8  # the asymmetry gain's bound, Q8: t_a c_a < 2^27


def octagon(a: int, b: int) -> int:
    """max + 3/8 min of two non-negative integers: a Euclidean norm's octagonal estimate."""
    hi, lo = (a, b) if a >= b else (b, a)
    return hi + ((3 * lo) >> 3)


def split_gains(jacobian: list[int]) -> tuple[int, int]:
    """(c_x, c_y) in Q8: round(256 J_max / J_a), from the Q12 Jacobians (> 0)."""
    top = max(jacobian)
    c = tuple((top * 256 + j // 2) // j for j in jacobian)
    if max(c) > C_MAX:
        raise NnikError(f"nn_vector: the axes' Jacobians {jacobian} (Q12) differ more than 16x; the split's gain "
                        "J_max / J_a would leave its format")
    return c


class NnVector(NeuralController):
    kind = "nn_vector"

    def _reset_state(self) -> None:
        self.c = split_gains(self.p["jacobian"])
        self.m1: int | None = None
        self.m2: int | None = None

    def tick(self, ref, pos) -> tuple[int, int]:
        ex, ey = (fx.s16(int(ref[a]) - int(pos[a])) for a in range(2))
        m = isqrt(ex * ex + ey * ey)
        m1 = m if self.m1 is None else self.m1
        m2 = m1 if self.m2 is None else self.m2
        rs = self.p["r_shift"]
        x = self._inputs((m, m - m1, m - 2 * m1 + m2, octagon(*(abs(fx.s16(int(ref[a]) >> rs)) for a in range(2)))))
        self.m2, self.m1 = m1, m
        net = self.nets[0]
        self._learn(net, x[0])
        net.u = u = fx.duty_out(net.forward(x, self.out_shift), self.duty_max)
        self.phase = (self.phase + 1) & (self.p["w1_every"] - 1)
        if m == 0:
            return 0, 0
        inv = (1 << 30) // m
        out = []
        for e_a, c_a in zip((ex, ey), self.c):
            unit = (e_a * inv + (1 << 15)) >> 16
            t = (u * unit + (1 << 10)) >> 11
            out.append(fx.duty_out((t * c_a) >> 3, self.duty_max))
        return out[0], out[1]

    def c_defines(self) -> dict[str, int]:
        return {**super().c_defines(), "NNIK_NN_R_SHIFT": self.p["r_shift"], "NNIK_NN_CX": self.c[0],
                "NNIK_NN_CY": self.c[1]}
