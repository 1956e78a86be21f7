"""The lut family: symmetry detection, range analysis, power-of-two index, integer model == C
(host, simavr, gpsim; fast and portable paths), accuracy."""

from __future__ import annotations

import re

import numpy as np
import pytest
from tests.implementations.lut_helpers import c_function_body, centred_corexy, host_check, host_vectors, problem, problem_from

from nnik.errors import NnikError
from nnik.implementations import FAMILIES
from nnik.implementations.accuracy import accuracy
from nnik.implementations.lut import LutImpl
from nnik.implementations.lut_table import detect_dependence, detect_parity
from nnik.implementations.verify import verify_host, verify_on_target

from tests.conftest import DATASETS, require_tool, write_toml

GALVO_K14 = {"k": [14, 14], "bits": 16, "W": 16, "fit": "lsq", "symmetry": True}


def test_registered():
    assert FAMILIES["lut"] is LutImpl


def test_symmetry_detected_on_the_galvo():
    # alpha depends on y only (even in x, odd in y); beta is odd in x and even in y
    assert detect_parity(problem("galvo_cba2012")) == [["even", "odd"], ["odd", "even"]]
    assert detect_parity(problem("galvo_dual_xy2")) == [["odd", "even"], ["even", "odd"]]


def test_no_symmetry_on_a_symmetric_domain_without_it(tmp_path):
    # a nonlinear CoreXY on a workspace centred on 0: the domain is symmetric, the IK is not
    p = centred_corexy(tmp_path)
    assert detect_parity(p) == [[None, None], [None, None]]
    im = LutImpl.fit(p, {"k": [15, 15]})
    assert im.table.grid.fold == (False, False)


def test_one_input_dependence_detected():
    assert detect_dependence(problem("galvo_cba2012")) == ["y", "xy"]  # alpha = atan(y / z) / 2
    assert detect_dependence(problem("galvo_dual_xy2")) == ["xy", "y"]
    assert detect_dependence(problem("corexy_nonlinear")) == ["xy", "xy"]
    assert detect_dependence(problem("corexy_measured")) == ["xy", "xy"]


def test_one_dimensional_table_for_a_one_input_output():
    p = problem("galvo_cba2012")
    two = LutImpl.fit(p, {**GALVO_K14, "separable": False})
    one = LutImpl.fit(p, GALVO_K14)
    assert one.table.dep == ("y", "xy") and two.table.dep == ("xy", "xy")
    assert one.model_bytes() == (8 + 64) * 2 < two.model_bytes()
    assert np.all(one.table.ent[0] == one.table.ent[0][:, :1])  # constant along x
    assert accuracy(one)["pre_max"] <= accuracy(two)["pre_max"] + 1e-3


def test_one_dimensional_tables_along_x_and_y_equal_host_c(tmp_path):
    # no shipped machine has an output that depends on x only: make one from the galvo's table
    im = LutImpl.fit(problem("galvo_cba2012"), {**GALVO_K14, "W": 8})
    t = im.table
    t.ent[0] = np.repeat(t.ent[0][:1, :], t.ent.shape[1], axis=0)
    t.ent[1] = np.repeat(t.ent[1][:, :1], t.ent.shape[2], axis=1)
    t.dep = ("x", "y")
    r = host_check(im, tmp_path)
    assert r["mismatches"] == 0


def test_measured_data_has_no_symmetry():
    assert detect_parity(problem("corexy_measured")) == [[None, None], [None, None]]


def test_quarter_table_and_its_accuracy():
    full = LutImpl.fit(problem("galvo_cba2012"), {**GALVO_K14, "symmetry": False, "separable": False})
    quarter = LutImpl.fit(problem("galvo_cba2012"), {**GALVO_K14, "separable": False})
    assert quarter.table.grid.fold == (True, True)
    assert quarter.model_bytes() * 3 < full.model_bytes()
    a = accuracy(quarter)
    assert a["points"] >= 1001 * 1001
    assert a["pre_max"] < 0.06  # measured 0.050 microstep, 256 bytes of table
    assert accuracy(full)["pre_max"] < 0.06


def test_eight_bit_fraction_reaches_the_issue_goal():
    im = LutImpl.fit(problem("galvo_cba2012"), {**GALVO_K14, "W": 8})
    assert accuracy(im)["pre_max"] < 0.1  # measured 0.074 microstep (goal: 0.1 in <= 420 AVR cycles)


def test_minimax_beats_least_squares_on_the_max():
    p = problem("galvo_cba2012")
    lsq = accuracy(LutImpl.fit(p, {**GALVO_K14, "k": [15, 15]}))["pre_max"]
    mm = accuracy(LutImpl.fit(p, {**GALVO_K14, "k": [15, 15], "fit": "minimax"}))["pre_max"]
    assert mm < lsq


def test_range_analysis_rejects_an_overflowing_table():
    p = problem("galvo_cba2012")
    with pytest.raises(NnikError, match="overflows"):
        LutImpl.fit(p, {**GALVO_K14, "fb": 12})  # 82 microsteps x 2^12 does not fit int16
    with pytest.raises(NnikError, match="overflows"):
        # cells of 2^18 um on the HBOT: node differences beyond int16 even at 0 fractional bits
        LutImpl.fit(problem("hbot_unicamp"), {"k": [18, 18], "bits": 16})


def test_bad_knobs_are_one_line_errors():
    p = problem("galvo_cba2012")
    for cfg, msg in (({"k": [14, 14], "W": 12}, "weight bits"), ({"k": [14, 14], "bits": 8}, "entry bits"),
                     ({"k": [14, 14], "fit": "cubic"}, "fit method"), ({"k": [4, 4]}, "nodes"),
                     ({"k": 14}, "two integer"), ({}, "two integer"), ({"k": [14, "x"]}, "two integer"),
                     ({"k": [14, 14], "bits": "16x"}, "entry bits")):
        with pytest.raises(NnikError, match=msg):
            LutImpl.fit(p, cfg)


def test_index_is_a_shift():
    im = LutImpl.fit(problem("galvo_cba2012"), GALVO_K14)
    body = c_function_body(im.render_source(), im.problem.name)
    assert "/" not in body
    index = [ln for ln in body.splitlines() if re.search(r"\b(ix|iy|fx|fy|tx|ty) =", ln)]
    assert len(index) >= 6
    for ln in index:
        assert "*" not in ln, ln  # no reciprocal multiply
    assert any("nnik_shr32(tx, 14)" in ln for ln in index)


@pytest.mark.parametrize("scenario,cfg", [
    ("galvo_cba2012", GALVO_K14),                                   # int16, quarter table
    ("galvo_cba2012", {**GALVO_K14, "bits": 32, "W": 8}),           # int32, 8-bit fraction
    ("corexy_nonlinear", {"k": [14, 14], "bits": 16}),              # no symmetry
    ("galvo_dual_xy2", {"k": [16, 15], "bits": 32}),                # 16-bit DAC: clamp to codes
    ("corexy_measured", {"k": [15, 15], "bits": 32}),               # measured rows
])
def test_integer_model_equals_host_c(tmp_path, scenario, cfg):
    r = host_check(LutImpl.fit(problem(scenario), cfg), tmp_path)
    assert r["points"] > 100_000
    assert r["mismatches"] == 0


def test_dac_outputs_stay_in_code_range():
    p = problem("galvo_dual_xy2")
    im = LutImpl.fit(p, {"k": [16, 15], "bits": 32})
    out = im.run(host_vectors(p, 2000)).out
    lo, hi = p.code_range
    assert out.min() >= lo and out.max() <= hi
    assert accuracy(im)["pre_max"] < 30  # coarse table: measured 26 LSB


def test_measured_fit_is_sane():
    im = LutImpl.fit(problem("corexy_measured"), {"k": [15, 15], "bits": 32})
    a = accuracy(im)
    assert a["points"] == 150
    assert a["pre_max"] < 3.0  # held-out rows, with their 2 um noise


def test_estimate_is_calibrated():
    im = LutImpl.fit(problem("galvo_cba2012"), {**GALVO_K14, "W": 8})
    for target in ("avr", "pic18"):
        e = im.estimate(target)
        assert e["validated"] is True  # the calibration matches today's C
        assert 200 < e["cycles"] < 1200
        assert e["flash_bytes"] > im.model_bytes()


@pytest.mark.parametrize("target,tool", [("avr", "simavr"), ("pic18", "gpsim")])
def test_bit_exact_on_the_chip_fast_and_portable(tmp_path, target, tool):
    require_tool(tool)
    im = LutImpl.fit(problem("galvo_cba2012"), {**GALVO_K14, "W": 8})
    fast = verify_on_target(im, target, tmp_path / "c", tmp_path / "wf", n_inside=40)
    port = verify_on_target(im, target, tmp_path / "c", tmp_path / "wp", portable=True, n_inside=40)
    assert fast["mismatches"] == 0 and port["mismatches"] == 0
    assert fast["cycles"] < port["cycles"]
    assert fast["cycles"] < (420 if target == "avr" else 1200)  # the issue's goals
    est = im.estimate(target)["cycles"]
    assert abs(est - fast["cycles"]) <= 0.03 * fast["cycles"]


def _small_galvo(tmp_path):
    # x off zero (no x fold: parity is tested on the symmetric hull of a field that straddles 0),
    # y symmetric (y fold); a few mm, so cells of 2^5..2^8 um
    text = (DATASETS / "galvo_cba2012.toml").read_text()
    text = text.replace("x_mm = [-100.0, 100.0]", "x_mm = [1.0, 6.0]").replace("y_mm = [-100.0, 100.0]",
                                                                               "y_mm = [-2.0, 2.0]")
    return problem_from(write_toml(tmp_path, text))


@pytest.mark.parametrize("target,tool", [("avr", "simavr"), ("pic18", "gpsim")])
def test_edge_geometries_bit_exact_on_the_chip(tmp_path, target, tool):
    """Small cells (byte-move index alignment), huge cells (right-shift alignment), one folded
    axis of two, int32 entries with an 8-bit fraction."""
    require_tool(tool)
    small = _small_galvo(tmp_path)
    cases = [(small, {"k": [7, 5], "W": 8}), (small, {"k": [6, 8], "W": 16, "bits": 32}),
             (problem("hbot_unicamp"), {"k": [18, 17], "bits": 32, "W": 8})]
    for i, (p, cfg) in enumerate(cases):
        im = LutImpl.fit(p, cfg)
        if p is small:
            assert im.table.grid.fold == (False, True)
        assert verify_host(im, tmp_path / f"c{i}")["mismatches"] == 0
        r = verify_on_target(im, target, tmp_path / f"c{i}", tmp_path / f"w{i}", n_inside=30)
        assert r["mismatches"] == 0, (cfg, r)
