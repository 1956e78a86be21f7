"""The neural controllers' cycle budgets on the simulated ATmega328P (avr-gcc -Os, simavr at 16 MHz),
issue 29 item 5: the controller's own computation (forward, backward and update, both axes, the
harness wrapper's call included) at most 12,000 cycles a tick for nn_axes and 7,000 for nn_vector,
worst tick at the default params (the learning schedule w1_every included) over long random
sequences (holds, ramps, reversals, jumps; small to saturating errors) with learning rates across
their range, and over runs that force the weights into their clamps (the clamp's slow path); the
chip bit-exact with the model all along."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.implementations.servo import make
from nnik.implementations.servo.c_check import avr_run, model_duties, model_sums
from nnik.implementations.servo.nn.params import OPTIONAL
from tests.conftest import require_tool
from tests.implementations.servo.nn_params import seeded_nn_params
from tests.implementations.servo.sequences import CFG, seeded_sequence

BUDGET = {"nn_axes": 12_000, "nn_vector": 7_000}


def _worst_tick(ctl, rows, tmp_path) -> int:
    res = avr_run(ctl, rows, tmp_path)
    assert (res["duty"] == model_duties(ctl, rows)).all() and (res["sum"] == model_sums(ctl, rows)).all()
    assert res["ram_bytes"] < 1024 and res["flash_bytes"] < 8192  # a quarter of the Uno's flash, half its RAM
    return int(res["cycles"].max())


@pytest.mark.parametrize("kind", sorted(BUDGET))
@pytest.mark.parametrize("case", range(3))
def test_worst_tick_within_the_budget(kind, case, tmp_path):
    require_tool("simavr")
    require_tool("avr-gcc")
    ctl = make(kind, seeded_nn_params(kind, 30 + case, CFG, eta_shift=(5, 11, 19)[case]), CFG)
    assert ctl.p["w1_every"] == OPTIONAL[kind]["w1_every"]  # the defaults are what is measured
    rows = seeded_sequence(40 + case)[:800]
    worst = _worst_tick(ctl, rows, tmp_path)
    assert ctl.updates > 0
    assert worst <= BUDGET[kind], f"{kind}: worst tick {worst} cycles (budget {BUDGET[kind]})"


@pytest.mark.parametrize("kind", sorted(BUDGET))
@pytest.mark.parametrize("sign", (-1, 1))
def test_worst_tick_within_the_budget_while_clamping(kind, sign, tmp_path):
    """Errors far beyond the inputs' range at the fastest rate: words clamp (the exact clamp runs
    after a row's or the output layer's block flagged it) and the tick still fits."""
    require_tool("simavr")
    require_tool("avr-gcc")
    p = seeded_nn_params(kind, 9, CFG, eta_shift=0)
    p["in_shift"] = [12, 12, 12, 12]
    ctl = make(kind, p, CFG)
    big = sign * (1 << 21)
    rows = np.array([[big * (k % 3 - 1) + 9 * k, -big * (k % 2), k, -k] for k in range(200)], dtype=np.int64)
    worst = _worst_tick(ctl, rows, tmp_path)
    assert ctl.clamps > 0
    assert worst <= BUDGET[kind], f"{kind}: worst tick {worst} cycles while clamping (budget {BUDGET[kind]})"
