"""What both neural controllers share: their nets made from params, the counters (updates, clamps,
held), the weights' checksum and norm, params() carrying the current weights, and the C macros and
arrays (the initial weights, copied into the chip's RAM weights on reset)."""

from __future__ import annotations

import math

from nnik.implementations.servo.base import check_duty_max
from nnik.implementations.servo.nn import formats as f
from nnik.implementations.servo.nn.net import Net
from nnik.implementations.servo.nn.params import check_params


class NeuralController:
    kind = ""

    def __init__(self, params: dict, cfg):
        self.p = check_params(self.kind, params)
        self.duty_max = check_duty_max(cfg.duty_max)
        self.out_shift = f.out_shift(self.duty_max)
        self.nets = [Net(w1, w2) for w1, w2 in zip(self.p["w1"], self.p["w2"])]
        self.reset()

    def reset(self) -> None:
        for n in self.nets:
            n.reset()
        self.counts = {"updates": 0, "clamps": 0, "held": 0}
        self.phase = 0  # ticks since the reset mod w1_every: which hidden rows learn (params.py)
        self._reset_state()

    def _reset_state(self) -> None:
        raise NotImplementedError

    def _learn(self, net: Net, d: int) -> None:
        net.learn(d, self.p["eta_shift"], self.duty_max, self.counts, self.phase, self.p["w1_every"])

    def _inputs(self, raw: tuple[int, ...]) -> list[int]:
        return [f.scale_in(r, s) for r, s in zip(raw, self.p["in_shift"])]

    @property
    def updates(self) -> int:
        return self.counts["updates"]

    @property
    def clamps(self) -> int:
        return self.counts["clamps"]

    @property
    def held(self) -> int:
        return self.counts["held"]

    def checksum(self) -> int:
        return sum(n.checksum() for n in self.nets) & 0xFFFF

    def weight_norm(self) -> float:
        return math.sqrt(sum(n.squares() for n in self.nets))

    def params(self) -> dict:
        """params with the current weights as the initial ones."""
        return {**self.p, "w1": [[list(r) for r in n.w1] for n in self.nets], "w2": [list(n.w2) for n in self.nets]}

    def c_defines(self) -> dict[str, int]:
        d = {f"NNIK_CTL_{self.kind.upper()}": 1, "NNIK_DUTY_MAX": self.duty_max, "NNIK_NN_NETS": len(self.nets),
             "NNIK_NN_ETA": self.p["eta_shift"], "NNIK_NN_OUT_SHIFT": self.out_shift,
             "NNIK_NN_JX": self.p["jacobian"][0], "NNIK_NN_JY": self.p["jacobian"][1],
             "NNIK_NN_W1_EVERY": self.p["w1_every"]}
        for i, s in enumerate(self.p["in_shift"]):
            d[f"NNIK_NN_IN_SHIFT_{i}"] = s
        return d

    def c_arrays(self) -> dict[str, list[int]]:
        """The initial master words: w1 as [net][hidden][input], w2 as [net][hidden], flat."""
        return {"NNIK_NN_W1_INIT": [w for net in self.p["w1"] for row in net for w in row],
                "NNIK_NN_W2_INIT": [w for net in self.p["w2"] for w in net]}
