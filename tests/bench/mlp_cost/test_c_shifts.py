"""The AVR C path's constant shifts are priced per bit as avr-gcc emits them (nnik.bench.mlp_cost.c_shifts).

* The calibration's per-bit coefficients are the recorded slopes, and those taken from the
  profile's shift tables are the tables' (no simulator).
* On simavr, a sample of the kernel primitives' slopes (and the output exponent's intercept)
  measured today are the recorded ones (avr-gcc -O2: the tanh input shift is 2 cycles a bit
  above 16, the output loop 5 a bit)."""

from __future__ import annotations

import pytest

from nnik.bench.mlp_cost import c_shifts as cs
from nnik.implementations.mlp.cost.calibrations import load_calibration

PROFILE = "avr-gcc-O2"


def _recorded():
    kc = load_calibration(PROFILE)["kernels"]["fast"]
    return kc, kc["c_shifts"]["slopes"]


def test_the_c_paths_shift_slopes_are_the_recorded_ones():
    kc, slopes = _recorded()
    assert set(slopes) == set(cs.SLOPES) | set(cs.INTERCEPTS.values())
    coef = kc["cycles"]["coef"]
    for k, v in slopes.items():
        assert coef[k] == v, k
    tables = load_calibration(PROFILE)["shift_tables"]["cycles"]
    for k, (src, (lo, hi)) in cs.SLOPES.items():
        if src in tables:
            assert slopes[k] == round((tables[src][hi] - tables[src][lo]) / (hi - lo), 3), k
    # the tanh input and the output shifts as the code is: an asr/ror pair, a 5-cycle loop step
    assert slopes["c:t_sh_n[17_23]"] == 2.0 and slopes["c:out_foldF_n[17_23]"] == 5.0


def test_the_refit_keeps_what_the_two_layer_path_shares():
    """A called tanh replacement's cost is keyed c: in the two-layer C path too: the refit
    of the one-layer path leaves those keys (and the data-dependent ones) as the full fit had them."""
    assert all(any(s in k for s in cs.KEPT) for k in ("c:tanh[lerp_mr]", "c:tanh_class[lerp_mr][r0-]", "c:sat_hit"))
    assert not any(s in "c:neuron_first" for s in cs.KEPT)


@pytest.fixture()
def avr():
    from nnik.targets import available

    ok, why = available("avr")
    if not ok:
        pytest.skip(why)


def test_the_primitives_slopes_on_simavr(avr, tmp_path, monkeypatch):
    sample = ("c:t_sh_n[17_23]", "c:out_foldF_n[17_23]", "c:out_e_pos_n[1_7]")  # the rest: the calibration
    monkeypatch.setattr(cs, "SLOPES", {k: cs.SLOPES[k] for k in sample})
    measured = cs.measure_slopes(PROFILE, tmp_path)
    _, slopes = _recorded()
    assert measured == {k: slopes[k] for k in measured}
