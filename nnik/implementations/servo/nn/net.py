"""One integer 4-8-1 network that learns online (formats: nn/formats.py): the forward pass on this
tick's inputs, and the backward pass and weight update with the previous tick's cache (inputs,
hidden outputs, duty) and this tick's delta_out. No biases: each controller gives its net an input
that plays a bias's part (nn_axes: the reference's speed; nn_vector: |R|), and the tanh units' odd
symmetry with a zero-error input gives zero output at rest.

Anti-windup: when the previous tick's output sat at +-duty_max and delta_out would push it further
out (same sign), the whole update of that net is skipped and counted in `held`.
"""

from __future__ import annotations

from nnik.implementations.servo.nn import formats as f


class Net:
    """w1 (8 x 4, row j = hidden unit j), w2 (8): int32 master words."""

    def __init__(self, w1: list[list[int]], w2: list[int]):
        self.w1_init = [list(map(int, row)) for row in w1]
        self.w2_init = list(map(int, w2))
        self.reset()

    def reset(self) -> None:
        self.w1 = [list(row) for row in self.w1_init]
        self.w2 = list(self.w2_init)
        self.x: list[int] | None = None  # the previous forward pass' cache
        self.h: list[int] = [0] * f.N_HID
        self.u = 0

    def forward(self, x: list[int], out_shift: int) -> int:
        """The Q8 duty accumulator for inputs x (Q3.12); caches x and the hidden outputs."""
        tanh = f.tanh_table()
        y = 0
        h = []
        for j in range(f.N_HID):
            row = self.w1[j]
            s = sum((row[i] >> 16) * x[i] for i in range(f.N_IN))
            hj = tanh[f.sat(s >> 12, f.I16) + 32768]
            h.append(hj)
            y += (self.w2[j] >> 16) * hj
        self.x, self.h = list(x), h
        return y >> out_shift

    def learn(self, d: int, eta: int, duty_max: int, counts: dict, phase: int = 0, every: int = 1) -> None:
        """Backward with the cached forward pass and delta_out d (Q3.12): the output layer's 8
        weights, and the first-layer rows of the hidden units j with j mod every == phase (phase in
        0 .. every - 1; every 1: all rows). counts gains updates (weights updated), clamps and held."""
        if self.x is None:
            return
        if (self.u >= duty_max and d > 0) or (self.u <= -duty_max and d < 0):
            counts["held"] += 1
            return
        x = self.x
        s1 = eta + f.W1_EXTRA
        d2 = f.rnd(d, eta & 7)
        for j in range(f.N_HID):
            hj, w2 = self.h[j], self.w2[j]  # delta_h uses the output weight of the forward pass
            self.w2[j] = self._clamp(w2 + f.rnd(d2 * hj, eta & ~7), f.W2_LIM, counts)
            if (j & (every - 1)) != phase:
                continue
            g = f.I16 - ((hj * hj) >> 15)
            t = f.sat((d * (w2 >> 16)) >> 12, f.I16)
            dh = f.rnd((t * g) >> 15, s1 & 7)
            row = self.w1[j]
            for i in range(f.N_IN):
                row[i] = self._clamp(row[i] + f.rnd(dh * x[i], s1 & ~7), f.W1_LIM, counts)
        counts["updates"] += f.N_HID + f.N_IN * (f.N_HID // every)

    @staticmethod
    def _clamp(w: int, lim: int, counts: dict) -> int:
        if w > lim or w < -lim:
            counts["clamps"] += 1
            return lim if w > 0 else -lim
        return w

    def checksum(self) -> int:
        return (sum(w & 0xFFFF for row in self.w1 for w in row) + sum(w & 0xFFFF for w in self.w2)) & 0xFFFF

    def squares(self) -> float:
        """The sum of the squared weights in real units (master / 2^28)."""
        sc = float(1 << f.MASTER_FRAC)
        return sum((w / sc) ** 2 for row in self.w1 for w in row) + sum((w / sc) ** 2 for w in self.w2)
