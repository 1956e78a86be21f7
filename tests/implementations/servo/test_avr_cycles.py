"""Each controller's C on the simulated ATmega328P (avr-gcc -Os, simavr at 16 MHz): its duties ==
the integer Python model at every tick (16-bit int on AVR), and its cycles per tick, measured with
Timer1 around each call over a random sequence (holds, ramps, reversals, jumps; saturating and
small errors). The issue's budget: the PID's computation <= 800 cycles per axis per tick; the
measured tick covers both axes (and the harness wrapper's call), so it must stay <= 1,600."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.implementations.servo import KINDS, make
from nnik.implementations.servo.c_check import avr_run, model_duties
from tests.conftest import require_tool
from tests.implementations.servo.sequences import CFG, seeded_gains, seeded_sequence

PID_BUDGET_PER_AXIS = 800


@pytest.mark.parametrize("kind", KINDS)
def test_chip_matches_the_model_and_its_cycles(kind, tmp_path):
    require_tool("simavr")
    require_tool("avr-gcc")
    rows = seeded_sequence(1)[:600]
    assert len(rows) >= 300
    g = seeded_gains(kind, 2)
    ctl = make(kind, g, CFG)
    res = avr_run(ctl, rows, tmp_path)
    model = model_duties(ctl, rows)
    bad = np.flatnonzero((res["duty"] != model).any(axis=1))
    assert bad.size == 0, f"tick {bad[0]}: chip {res['duty'][bad[0]].tolist()} model {model[bad[0]].tolist()}"
    cyc = res["cycles"]
    assert cyc.min() > 50  # a real measurement (the call did run)
    if kind == "pid":
        assert cyc.max() <= 2 * PID_BUDGET_PER_AXIS, f"PID: {cyc.max()} cycles a tick for two axes"
