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
    assert abs(est["cycles"] / r["cycles"] - 1) < 0.15, (est, r["cycles"])


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


def test_calibration_is_measured():
    cal = json.loads(wide.CALIBRATION.read_text())
    assert set(cal["targets"]) == {"avr", "pic18"} and len(cal["measurements"]) >= 6
    x = np.array([[1.0] + [m[f] for f in wide.FEATURES] for m in cal["measurements"]])
    for t in ("avr", "pic18"):
        pred = x @ np.array(cal["targets"][t]["cycles"])
        meas = np.array([m[t]["cycles"] for m in cal["measurements"]])
        assert np.all(np.abs(pred / meas - 1) < 0.15)
