"""nn_axes: one online-learning 4-8-1 network per axis (issue 29, item 1; formats: formats.py).

Inputs per axis, e = ref - pos in counts saturated to +-2^20 (so the differences fit int32):
    x = (e[k], e[k] - e[k-1], e[k] - 2 e[k-1] + e[k-2], v_ref[k]),  v_ref = ref[k] - ref[k-W]
the seed's PD^2 law on e[k], e[k-1], e[k-2] as a linear recombination of the same three errors (the
same information, better conditioned: the three columns are nearly equal at 5 ms), plus the
reference's speed over W ticks (window.RefHistory, as pdff) in place of the seed's reference input
on trajectories; it plays a bias's part (the speed feedforward). After a reset the history is the
first tick's error and reference (differences 0).

Each tick: first learn with the previous tick's forward pass and this tick's error
(delta_out = sat16((x_0 J_axis) >> 12), x_0 the scaled error input, J the axis' Jacobian in Q12),
then the forward pass: duty = duty_out(y >> out_shift).
"""

from __future__ import annotations

from nnik.implementations.servo import fixed as fx
from nnik.implementations.servo.nn import formats as f
from nnik.implementations.servo.nn.controller import NeuralController
from nnik.implementations.servo.window import RefHistory

E_MAX = 1 << 20


class NnAxes(NeuralController):
    kind = "nn_axes"

    def _reset_state(self) -> None:
        self.hist = [RefHistory(self.p["win"]) for _ in range(2)]
        self.e1: list[int] | None = None
        self.e2: list[int] | None = None

    def tick(self, ref, pos) -> tuple[int, int]:
        e = [f.sat(int(ref[a]) - int(pos[a]), E_MAX) for a in range(2)]
        e1 = self.e1 or e
        e2 = self.e2 or e1
        out = []
        for a, net in enumerate(self.nets):
            r = int(ref[a])
            v = f.sat(r - self.hist[a].push(r)[0], E_MAX)
            x = self._inputs((e[a], e[a] - e1[a], e[a] - 2 * e1[a] + e2[a], v))
            d = f.sat((x[0] * self.p["jacobian"][a]) >> f.Q_J, f.I16)
            self._learn(net, d)
            net.u = fx.duty_out(net.forward(x, self.out_shift), self.duty_max)
            out.append(net.u)
        self.e2, self.e1 = e1, e
        self.phase = (self.phase + 1) & (self.p["w1_every"] - 1)
        return out[0], out[1]

    def c_defines(self) -> dict[str, int]:
        w = self.p["win"]
        return {**super().c_defines(), "NNIK_CTL_WIN": w, "NNIK_CTL_WIN_LOG2": w.bit_length() - 1}
