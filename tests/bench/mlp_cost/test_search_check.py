"""The estimator on the networks `nnik search` proposes (nnik.bench.mlp_cost.search_check): random
architectures of its MLP space (one or two hidden layers of its widths, full, residual and
residual with a DAC clamp, int8 and int16 weights, the fast kernel, every tanh replacement).

* Without a simulator: a network inside what the calibration measured (its counts are in the
  span of the calibration networks', nnik.implementations.mlp.cost.span) is validated and states
  the measured band -- on both AVR profiles (all but a rare few combinations of counts, at most
  5 % of the draws, which state no band), and on PIC18 wherever SDCC builds the network in
  reasonable time (the assembly body: one layer, the kernel's own tanh; the C path of small
  networks).  Networks outside that are not validated and state no band.
* The claimed bands are the measured ones (recorded search-space check and sweep) and at most
  3 %.
* On simavr and gpsim, with draws no recorded check used: each validated estimate is within the
  band it states.  CI measures a sample (NNIK_ESTIMATE_DRAWS, default 6 AVR and 2 PIC18
  networks); `make bench` runs the full check (nnik.bench.estimate)."""

from __future__ import annotations

import os
import sys

import pytest

from nnik.bench.mlp_cost import search_check as sc
from nnik.implementations.mlp.cost.calibrations import GOAL_CYCLES_PCT, load_calibration
from nnik.implementations.mlp.cost.coverage import measurable
from nnik.implementations.mlp.cost.fast_features import fast_path
from nnik.implementations.mlp.cost.predict import estimate, stated_cycles_error_pct
from nnik.implementations.mlp.cost.synthetic import synthetic_model

SEED = 20270101  # not the recorded check's seed: these draws played no part in the stated bound
DRAWS = int(os.environ.get("NNIK_ESTIMATE_DRAWS", "6"))
PROFILES = ("avr-gcc-Os", "avr-gcc-O2", "pic18-sdcc")


def _target(prof: str) -> str:
    return "pic18" if prof.startswith("pic18") else "avr"


@pytest.fixture(scope="module")
def draws():
    specs = sc.draw_specs(40, SEED + 1)
    return [(sp, synthetic_model(sp, kernel=sc.KERNEL)) for sp in specs]


# per profile: why its claim is still open (xfail strict); none open.  avr-gcc-O2's one-layer C
# path missed by up to -2.75 % (seed 31: band 3.3 %) while its shifts were priced by fitted slopes
# of the wrong sign; priced as the code is (nnik.bench.mlp_cost.c_shifts, test_c_shifts) it is
# -2.42..+1.13 % (band 3.0 %)
OPEN: dict[str, str] = {}


def _per_profile():
    return [pytest.param(p, marks=[pytest.mark.xfail(strict=True, reason=OPEN[p])] if p in OPEN else [])
            for p in PROFILES]


@pytest.mark.parametrize("prof", _per_profile())
def test_every_search_network_is_validated_where_it_can_be_measured(draws, prof):
    kinds = {(len(sp.hidden), sp.weight_bits, sp.tanh == "", sp.scenario) for sp, _ in draws}
    assert len(kinds) >= 16  # depths, weight widths, tanh replacements and output modes all drawn
    outside = []
    for sp, im in draws:
        e = estimate(im, _target(prof), prof, kernel=sc.KERNEL)
        if measurable(sp, im, _target(prof)) and not e["validated"] and _target(prof) == "avr":
            # AVR: a combination of counts no calibration network had (an output shift regime with
            # a DAC clamp, an affine coefficient class, ...; 10 of 640 draws of seeds 20270102, 9001
            # and 4444): extrapolated, so it states no band
            assert e["cycles_error_pct"] is None, (sp.label, prof)
            assert any(n.startswith("a combination of counts no calibration network had") for n in e["notes"])
            outside.append(sp.label)
        elif measurable(sp, im, _target(prof)):
            assert e["validated"], (sp.label, prof, e["notes"])
            assert 0 < e["cycles_error_pct"] <= GOAL_CYCLES_PCT, (sp.label, prof)
        else:  # SDCC's build of the unrolled C of a larger network: never measured, no band
            assert fast_path(im, "pic18") == "c" and not e["validated"] and e["cycles_error_pct"] is None
    assert len(outside) <= len(draws) // 20, outside  # rare: at most 5 % of the search's draws


def test_claimed_bands_are_the_measured_ones():
    for prof in PROFILES:
        rec = load_calibration(prof)["search_check"]["fast"]
        assert rec["stated_cycles_err_pct"] == sc.band(rec["max_abs_cycles_err_pct"])
        assert rec["networks"] >= 5 and rec["residual_networks"] >= 1, prof


@pytest.mark.parametrize("prof", _per_profile())
def test_claimed_bands_are_the_measured_ones_and_within_3_percent(prof):
    cal = load_calibration(prof)
    rec = cal["search_check"]["fast"]
    assert rec["stated_cycles_err_pct"] == sc.band(rec["max_abs_cycles_err_pct"])
    assert rec["stated_cycles_err_pct"] <= GOAL_CYCLES_PCT, prof
    assert rec["networks"] >= 18 and rec["residual_networks"] >= 5 and rec["int8_networks"] >= 3, prof
    sweep = cal["validation"]["fast"]["by_layers"]
    for layers, s in sweep.items():
        assert s["max_abs_cycles_err_pct"] <= GOAL_CYCLES_PCT, (prof, layers)
    stated = stated_cycles_error_pct(cal, "fast", sweep["1"])
    assert stated == max(rec["stated_cycles_err_pct"], sweep["1"]["max_abs_cycles_err_pct"]) <= GOAL_CYCLES_PCT


def test_a_band_over_3_percent_is_caught(monkeypatch):
    """The claim test reads the calibration: a wider recorded band fails it."""
    cal = load_calibration("avr-gcc-Os")
    wide = {**cal, "search_check": {"fast": {**cal["search_check"]["fast"], "max_abs_cycles_err_pct": 9.5,
                                             "stated_cycles_err_pct": sc.band(9.5)}}}
    monkeypatch.setattr(sys.modules[__name__], "load_calibration", lambda p: wide)
    with pytest.raises(AssertionError):
        test_claimed_bands_are_the_measured_ones_and_within_3_percent("avr-gcc-Os")


@pytest.fixture()
def chips():
    from nnik.targets import available

    for t in ("avr", "pic18"):
        ok, why = available(t)
        if not ok:
            pytest.skip(why)


def test_measured_error_is_within_the_stated_band_on_fresh_networks(chips, tmp_path):
    specs = sc.draw_specs(4 * DRAWS, SEED)
    avr = specs[:DRAWS]
    ims = {sp.label: synthetic_model(sp, kernel=sc.KERNEL) for sp in specs}
    pic = [sp for sp in specs[DRAWS:] if measurable(sp, ims[sp.label], "pic18")
           and fast_path(ims[sp.label], "pic18") == "asm"][:max(1, DRAWS // 3)]
    rows = sc.check(avr, ["avr-gcc-Os"], n_vec=40, workdir=tmp_path, verbose=False)
    rows += sc.check(avr[: DRAWS // 2], ["avr-gcc-O2"], n_vec=40, workdir=tmp_path, verbose=False)
    rows += sc.check(pic, ["pic18-sdcc"], n_vec=40, workdir=tmp_path, verbose=False)
    assert len(rows) == len(avr) + DRAWS // 2 + len(pic) and pic
    assert any(r["validated"] for r in rows)
    for r in rows:
        if r["validated"]:
            assert abs(r["cycles_err_pct"]) <= r["stated_pct"], r
        else:
            assert r["stated_pct"] is None, r


def test_asm_body_with_output_finished_in_c_is_priced_apart(chips, tmp_path):
    """A one-layer search network (assembly body, output F = 22 shifted in assembly) was once
    validated and 36 % off on AVR: the output stage's shift counts were shared between outputs
    finished in assembly and outputs the body hands to C, so its counts looked like a combination
    of calibrated ones. They are counted apart now (cfin_*); the estimate is within its stated
    band, or not validated."""
    from nnik.implementations.mlp.cost.fast_features import fast_counts_prefixed
    from nnik.implementations.mlp.cost.synthetic import CalSpec

    sp = CalSpec("galvo", (5,), tanh="", weight_bits=16, seed=982387, gain=0.687801)
    im = synthetic_model(sp, kernel=sc.KERNEL)
    assert fast_path(im, "avr") == "asm"
    row = fast_counts_prefixed(im, False, "avr")
    finished_in_c = "asm:out_c_finish" in row
    assert not any(k.startswith("asm:cfin_") for k in row) or finished_in_c
    assert not finished_in_c or not any(k.startswith(("asm:out_F", "asm:out_e_")) for k in row)
    for r in sc.check([sp], ["avr-gcc-Os", "avr-gcc-O2"], n_vec=20, workdir=tmp_path, verbose=False):
        if r["validated"]:
            assert abs(r["cycles_err_pct"]) <= r["stated_pct"], r
        else:
            assert r["stated_pct"] is None, r
