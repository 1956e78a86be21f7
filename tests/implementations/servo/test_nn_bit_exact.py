"""The neural controllers' C == their integer Python model at every tick, duties AND the weights'
checksum (nnik_ctl_sum), on the host (gcc with the undefined-behaviour and address sanitizers, so
an int32 overflow fails) and on the simulated ATmega328P (avr-gcc -Os, simavr): random params
anywhere in their formats, random reference/position sequences, learning every tick, clamps forced
by extreme inputs (counted, no wrap), and a reset restoring the initial weights."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik.implementations.servo import NEURAL, make
from nnik.implementations.servo.c_check import avr_run, host_run, model_duties, model_sums
from nnik.implementations.servo.nn import formats as f
from tests.conftest import require_tool
from tests.implementations.servo.nn_params import nn_params, seeded_nn_params
from tests.implementations.servo.sequences import CFG, seeded_sequence, sequences


def _first_bad(c: dict, duty: np.ndarray, sums: np.ndarray) -> str:
    bad = np.flatnonzero((c["duty"] != duty).any(axis=1) | (c["sum"] != sums))
    if bad.size == 0:
        return ""
    k = bad[0]
    return f"tick {k}: C duty {c['duty'][k].tolist()} sum {c['sum'][k]}, model {duty[k].tolist()} sum {sums[k]}"


def _masters(ctl) -> list[int]:
    return [w for n in ctl.nets for row in n.w1 for w in row] + [w for n in ctl.nets for w in n.w2]


@pytest.mark.parametrize("kind", NEURAL)
@given(data=st.data())
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_host_c_matches_the_model_duties_and_checksum(kind, data):
    ctl = make(kind, data.draw(nn_params(kind)), CFG)
    rows = data.draw(sequences())
    duty, sums = model_duties(ctl, rows), model_sums(ctl, rows)
    assert np.abs(duty).max() <= CFG.duty_max
    assert max(abs(w) for w in _masters(ctl)) <= f.W1_LIM  # held to the format: nothing wraps
    problem = _first_bad(host_run(ctl, rows), duty, sums)
    assert not problem, problem


@pytest.mark.parametrize("kind", NEURAL)
def test_weights_learn_every_tick_with_an_error(kind):
    """A fast learning rate and an error on every tick (small enough to leave the duty unsaturated):
    the checksum changes on every tick after the first, and the C follows it."""
    ctl = make(kind, seeded_nn_params(kind, 4, CFG, eta_shift=6), CFG)
    rows = np.array([[300 * k, 200 * k, 300 * k - 40 - (k % 7) * 5, 200 * k + 30 - (k % 5) * 4] for k in range(120)],
                    dtype=np.int64)
    duty, sums = model_duties(ctl, rows), model_sums(ctl, rows)
    changed = np.count_nonzero(np.diff(sums))
    assert changed == len(rows) - 1, f"the weights changed on {changed} of {len(rows) - 1} ticks"
    assert ctl.updates > 0 and ctl.held == 0 and ctl.weight_norm() != make(kind, ctl.p, CFG).weight_norm()
    problem = _first_bad(host_run(ctl, rows), duty, sums)
    assert not problem, problem


@pytest.mark.parametrize("kind", NEURAL)
@given(seed=st.integers(0, 2 ** 16), sign=st.sampled_from([-1, 1]))
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_extreme_inputs_clamp_the_weights_counted_and_unwrapped(kind, seed, sign):
    """Errors far beyond every input's range with the fastest rate drive the master words into their
    clamps: each clamp is counted, every word stays in its format, and the C agrees bit for bit."""
    p = seeded_nn_params(kind, seed, CFG, eta_shift=0)
    p["in_shift"] = [12, 12, 12, 12]
    ctl = make(kind, p, CFG)
    big = sign * (1 << 21)
    rows = np.array([[big * (k % 3 - 1) + 9 * k, -big * (k % 2), k, -k] for k in range(80)], dtype=np.int64)
    duty, sums = model_duties(ctl, rows), model_sums(ctl, rows)
    assert ctl.clamps > 0, (ctl.clamps, ctl.updates, ctl.held)
    assert all(abs(w) <= f.W1_LIM for n in ctl.nets for row in n.w1 for w in row)
    assert all(abs(w) <= f.W2_LIM for n in ctl.nets for w in n.w2)
    problem = _first_bad(host_run(ctl, rows), duty, sums)
    assert not problem, problem


@pytest.mark.parametrize("kind", NEURAL)
def test_a_reset_restores_the_initial_weights(kind):
    ctl = make(kind, seeded_nn_params(kind, 5, CFG, eta_shift=3), CFG)
    start_sum, start_params = ctl.checksum(), ctl.params()
    rows = seeded_sequence(6)[:60]
    duty, sums = model_duties(ctl, rows), model_sums(ctl, rows)
    assert ctl.checksum() != start_sum and ctl.params() != start_params  # it learnt
    ctl.reset()
    assert ctl.checksum() == start_sum and ctl.params() == start_params
    assert ctl.updates == ctl.clamps == ctl.held == 0
    twice = host_run(ctl, np.vstack([rows, rows]), reset_before=(60,))
    assert (twice["duty"][:60] == duty).all() and (twice["duty"][60:] == duty).all()
    assert (twice["sum"][:60] == sums).all() and (twice["sum"][60:] == sums).all()
    carried = host_run(ctl, np.vstack([rows, rows]))
    assert (carried["sum"][60:] != sums).any()  # without the reset the learnt weights carry


@pytest.mark.parametrize("kind", NEURAL)
def test_the_chip_matches_the_model_duties_and_checksum(kind, tmp_path):
    require_tool("simavr")
    require_tool("avr-gcc")
    rows = seeded_sequence(7)[:500]
    ctl = make(kind, seeded_nn_params(kind, 8, CFG), CFG)
    res = avr_run(ctl, rows, tmp_path)
    duty, sums = model_duties(ctl, rows), model_sums(ctl, rows)
    assert ctl.updates > 0
    problem = _first_bad(res, duty, sums)
    assert not problem, problem
    assert res["cycles"].min() > 500  # a real measurement: the nets did run


@pytest.mark.parametrize("kind", NEURAL)
def test_the_chip_clamps_as_the_model(kind, tmp_path):
    require_tool("simavr")
    require_tool("avr-gcc")
    p = seeded_nn_params(kind, 9, CFG, eta_shift=0)
    p["in_shift"] = [12, 12, 12, 12]
    ctl = make(kind, p, CFG)
    big = 1 << 21
    rows = np.array([[big * (k % 3 - 1), -big * (k % 2), 0, 0] for k in range(120)], dtype=np.int64)
    res = avr_run(ctl, rows, tmp_path)
    duty, sums = model_duties(ctl, rows), model_sums(ctl, rows)
    assert ctl.clamps > 0
    problem = _first_bad(res, duty, sums)
    assert not problem, problem
