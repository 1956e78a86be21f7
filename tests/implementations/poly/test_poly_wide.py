"""The poly family's wide path (width 32, issue 15): where 16-bit Horner limits a 16-bit DAC
gimbal, int32 values with exact 64-bit products reach its 0.15 LSB; the integer model is the C
on the host (sanitizers), on simavr and on gpsim; the ladder reaches the wide rungs only once the
16-bit ones fall short; its cost model is calibrated on the simulators."""

from __future__ import annotations

import json

import numpy as np
import pytest
from tests.implementations.lut_helpers import host_check, problem, problem_from

from nnik.errors import NnikError
from nnik.implementations.accuracy import accuracy
from nnik.implementations.poly import int_model as poly_int
from nnik.implementations.poly import wide
from nnik.implementations.poly.family import PolyImpl
from nnik.implementations.verify import verify_on_target
from nnik.selection import fit_ladder

from tests.conftest import require_tool

DAC16 = """name = "dac16"
[mechanism]
kind = "galvo_gimbal"
z_mm = 250.0
[actuator]
kind = "dac"
bits = 16
optical_range_deg = 40.0
[workspace]
x_mm = [-80.0, 80.0]
y_mm = [-80.0, 80.0]
[export]
input_unit_um = 0.25
[target]
max_error = 0.15
"""
W32 = {"width": 32, "coef_bits": 32}


@pytest.fixture(scope="module")
def dac16(tmp_path_factory):
    p = tmp_path_factory.mktemp("dac16") / "dac16.toml"
    p.write_text(DAC16)
    return problem_from(p)


def test_the_wide_path_reaches_what_16_bits_cannot(dac16):
    narrow = accuracy(PolyImpl.fit(dac16, {"degree": 9, "lsb": True}))["pre_max"]
    im = PolyImpl.fit(dac16, {"degree": 7, **W32})
    acc = accuracy(im)
    assert narrow > 0.15  # 16-bit Horner: the values' rounding, not the degree, limits it
    assert acc["pre_max"] < 0.05 < 0.15
    assert "32-bit Horner" in im.describe()
    assert max(abs(v) for st in im.prog.steps for v in im.prog.bounds[st.dst]) > 32767  # values use 32 bits


def test_wide_is_bit_exact_on_the_host(dac16, tmp_path):
    im = PolyImpl.fit(dac16, {"degree": 9, **W32})
    r = host_check(im, tmp_path)
    assert r["bit_exact"] and r["mismatches"] == 0 and r["points"] > 100_000


@pytest.mark.parametrize("target, tool", [("avr", "simavr"), ("pic18", "gpsim")])
def test_wide_is_bit_exact_on_the_simulated_chips(dac16, tmp_path, target, tool):
    require_tool(tool)
    im = PolyImpl.fit(dac16, {"degree": 7, **W32})
    r = verify_on_target(im, target, tmp_path / "c", tmp_path / "b", n_inside=40)
    assert r["bit_exact"] and r["mismatches"] == 0, r
    est = im.estimate(target)
    assert abs(est["cycles"] / r["cycles"] - 1) < 0.15, (est, r["cycles"])  # the stated band: test_cost_models


def test_wide_range_analysis_proves_int32_and_int64():
    im = PolyImpl.fit(problem("galvo_cba2012"), {"degree": 5, **W32})
    ur = wide.urange(im)
    assert poly_int.prove(im.prog, ur, (0, 0), 32) is None
    # a product that leaves int64 is caught by the proof
    st = im.prog.steps[0]
    bad = poly_int.Program(steps=[poly_int.Step(st.dst, st.a, 2**31 - 1, 2**62, 0, None)], outs=[])
    assert poly_int.prove(bad, ur, (0, 0), 32) == st.dst


@pytest.mark.parametrize("knobs", [{"width": 24}, {"width": 32, "split": True}, {"width": 32, "lsb": True},
                                   {"width": 32, "coef_bits": 16}])
def test_bad_wide_knobs_are_one_clear_error(knobs):
    with pytest.raises(NnikError, match="poly: "):
        PolyImpl.fit(problem("galvo_cba2012"), {"degree": 3, "coef_bits": 32, **knobs})


def test_the_ladder_reaches_the_wide_rungs_after_16_bits(dac16):
    lad = PolyImpl.ladder(dac16)
    widths = [c.get("width", 16) for c in lad]
    assert widths == sorted(widths) and 32 in widths  # every 16-bit rung first
    cands = fit_ladder(dac16, ["poly"], max_error=0.15)
    met = [c for c in cands if c.impl is not None and c.meets(0.15)]
    assert met and all(c.config.get("width") == 32 for c in met)
    # a target the 16-bit rungs meet never fits a wide one
    easy = fit_ladder(problem("galvo_cba2012"), ["poly"], max_error=0.05)
    assert not [c for c in easy if c.impl is not None and c.config.get("width") == 32]


def test_calibration_is_the_fit_of_its_own_measurements():
    """The shipped coefficients are the least-squares fit of the measurements stored beside them
    (nnik.bench.poly32_calibration), on both chips, and that fit explains each of them."""
    from nnik.implementations.poly import wide_cost

    cal = json.loads(wide.CALIBRATION.read_text())
    assert set(cal["targets"]) == {"avr", "pic18"}
    for t in ("avr", "pic18"):
        rows = [m for m in cal["measurements"] if t in m]
        assert len(rows) >= 3 * len(wide_cost.FEATURES[t]), t
        assert np.allclose(wide_cost.fit(rows, t)["cycles"], cal["targets"][t]["cycles"])
        pred = np.array([wide_cost.predict(cal["targets"][t]["cycles"], m[t], wide_cost.FEATURES[t], m[t]["known"])
                         for m in rows])
        meas = np.array([m[t]["cycles"] for m in rows])
        assert np.all(np.abs(pred / meas - 1) < 0.1), t


def test_the_operands_signs_are_priced_from_the_program(dac16):
    """negs: the mean count of negative operands over the domain grid, from the weights and the
    program's own values (bounded by two per call; a product of u and a constant is negative on
    the part of the domain where u < 0)."""
    from nnik.implementations.poly import wide_cost

    im = PolyImpl.fit(dac16, {"degree": 3, **W32})
    c = wide_cost.counts(im, "avr")
    assert 0 < c["negs"] < 2 * c["calls"] and c["calls"] == len(im.prog.steps) + sum(len(o.terms) for o in im.prog.outs)
    x, y = wide_cost.domain_grid(im)
    assert wide_cost.counts(im, "avr", (x, y))["negs"] == c["negs"]
    # the signs depend on where in the domain the inputs fall: another part gives another mean
    left = x <= np.median(x)
    assert wide_cost.counts(im, "avr", (x[left], y[left]))["negs"] != c["negs"]
    assert wide_cost.counts(im, "pic18")["known"] == 0 < c["known"]


@pytest.mark.parametrize("degree", [1, 3, 5])
def test_calls_that_skip_the_bit_pick_are_counted_from_the_c(dac16, degree):
    """f0_calls: the NAME_mac calls whose shift f is 0 (on SDCC they return the low word and skip
    NAME_bits), read back from the calls the emitted C makes."""
    import re

    from nnik.implementations.poly import wide_cost

    im = PolyImpl.fit(dac16, {"degree": degree, **W32})
    shifts = [int(f) for f in re.findall(r"_mac\([^;]*?, (\d+)\)", "\n".join(wide.lines(im)))]
    c = wide_cost.counts(im, "pic18")
    assert len(shifts) == c["calls"]
    assert c["f0_calls"] == shifts.count(0)
    assert c["high"] == sum(f >= 32 for f in shifts)
