"""Each controller's C == its integer Python model, tick by tick: on the host (gcc with the
undefined-behaviour and address sanitizers, so an int32 overflow in the C fails too) over random
gains anywhere in their formats and random reference/position sequences (holds, ramps, reversals,
jumps; errors from none to far beyond saturation)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from nnik.implementations.servo import KINDS, make
from nnik.implementations.servo.c_check import host_duties, model_duties
from tests.implementations.servo.sequences import CFG, gains, make_plain, sequences


@pytest.mark.parametrize("kind", KINDS)
def test_host_c_matches_the_model_every_tick(kind):
    @settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(g=gains(kind), rows=sequences())
    def check(g, rows):
        ctl = make(kind, g, CFG)
        model = model_duties(ctl, rows)
        assert np.abs(model).max() <= CFG.duty_max
        c = host_duties(ctl, rows)
        bad = np.flatnonzero((c != model).any(axis=1))
        assert bad.size == 0, f"tick {bad[0]}: C {c[bad[0]].tolist()} model {model[bad[0]].tolist()} row {rows[bad[0]].tolist()}"

    check()


@pytest.mark.parametrize("kind", KINDS)
def test_a_reset_starts_afresh(kind):
    """Running a sequence, resetting and running it again gives the same duties (Python and C)."""
    rows = np.array([[100 * k, 50 * k, 90 * k, 55 * k] for k in range(20)], dtype=np.int64)
    ctl = make(kind, make_plain(kind), CFG)
    first = model_duties(ctl, rows)
    assert (model_duties(ctl, rows) == first).all()
    twice = host_duties(ctl, np.vstack([rows, rows]), reset_before=(20,))
    assert (twice[:20] == first).all() and (twice[20:] == first).all()
    assert (host_duties(ctl, np.vstack([rows, rows]))[20:] != first).any()  # without the reset, state carries

