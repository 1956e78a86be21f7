"""The poly family: symmetry from the truth (and none where the domain or the data do not allow
it), the range analysis, integer model == C (host with sanitizers on 10^5 points; simavr and
gpsim on the fast and portable paths), accuracy, and the cost model's calibration key."""

from __future__ import annotations

import json

import numpy as np
import pytest
from tests.implementations.lut_helpers import centred_corexy, host_vectors, problem, problem_from

from nnik.errors import NnikError
from nnik.implementations import FAMILIES
from nnik.implementations.accuracy import accuracy
from nnik.implementations.poly.family import PolyImpl
from nnik.implementations.poly import fit as poly_fit
from nnik.implementations.poly.fit import NO_SYMMETRY, detect_symmetry
from nnik.implementations.verify import verify_host, verify_on_target

from tests.conftest import DATASETS, require_tool, write_toml

CBA5 = {"degree": 5}
DUAL5 = {"degree": 5, "split": True, "rounding": False}
COREXY2 = {"degree": 2, "lsb": True, "split": True}


def test_registered():
    assert FAMILIES["poly"] is PolyImpl


def test_symmetry_found_in_the_galvo_truth():
    cba = detect_symmetry(problem("galvo_cba2012"))
    assert [s.label() for s in cba] == ["independent of x, odd in y", "odd in x, even in y"]
    dual = detect_symmetry(problem("galvo_dual_xy2"))
    assert [s.label() for s in dual] == ["odd in x, even in y", "independent of x, odd in y"]


def test_parity_about_zero_holds_on_an_off_centre_field(tmp_path):
    # the gimbal with x in [-50, 150] mm: the IK is odd in x about x = 0 whatever the field (issue
    # 15), so the parity is tested on the field's symmetric hull and the polynomial is centred on 0
    text = (DATASETS / "galvo_cba2012.toml").read_text().replace("x_mm = [-100.0, 100.0]", "x_mm = [-50.0, 150.0]")
    p = problem_from(write_toml(tmp_path, text))
    sym = detect_symmetry(p)
    assert sym[1].label() == "odd in x, even in y"
    assert sym[0].label() == "independent of x, odd in y"
    assert poly_fit.axis_maps(p)[0].c == 0
    im = PolyImpl.fit(p, {"degree": 3})
    assert all(i % 2 == 1 for i, _ in im.coefs[1][1])  # only odd powers of u
    assert accuracy(im)["pre_max"] < accuracy(PolyImpl.fit(p, {"degree": 1}))["pre_max"]


def test_no_parity_where_the_ik_has_none_on_the_hull(tmp_path):
    # off zero on x: no mirror image inside any hull, so no parity in x
    text = (DATASETS / "galvo_cba2012.toml").read_text().replace("x_mm = [-100.0, 100.0]", "x_mm = [20.0, 150.0]")
    p = problem_from(write_toml(tmp_path, text))
    assert detect_symmetry(p)[1].label() == "even in y"
    im = PolyImpl.fit(p, {"degree": 3})
    assert any(i % 2 == 0 and i > 0 for i, _ in im.coefs[1][1])  # even powers of u are kept


def test_no_symmetry_in_an_asymmetric_ik_on_a_symmetric_domain(tmp_path):
    p = centred_corexy(tmp_path)
    assert [s.label() for s in detect_symmetry(p)] == ["no symmetry", "no symmetry"]


def test_measured_data_get_no_symmetry():
    assert detect_symmetry(problem("corexy_measured")) == [NO_SYMMETRY, NO_SYMMETRY]


def test_range_analysis_rejects_an_overflowing_config():
    with pytest.raises(NnikError, match="cannot prove"):
        PolyImpl.fit(problem("galvo_cba2012"), {**CBA5, "guard": -1})
    im = PolyImpl.fit(problem("galvo_cba2012"), CBA5)
    assert all(-32768 <= lo and hi <= 32767 for k, (lo, hi) in im.prog.bounds.items() if not k.startswith("out"))


@pytest.mark.parametrize("knobs", [{"degree": 0}, {"colour": 1}, {"fit": "l1"}, {"coef_bits": 24}, {"split": "yes"}])
def test_bad_knobs_are_one_clear_error(knobs):
    with pytest.raises(NnikError, match="poly"):
        PolyImpl.fit(problem("galvo_cba2012"), knobs)


@pytest.mark.parametrize("name, unit, cfg", [
    ("galvo_cba2012", None, CBA5),
    ("galvo_cba2012", None, {"degree": 7, "coef_bits": 32, "split": True, "fit": "lsq"}),
    ("galvo_dual_xy2", None, DUAL5),  # a DAC (clamped code range), quarter-micrometre inputs
    ("galvo_dual_xy2", 1.0, {"degree": 5, "coef_bits": 32, "split": [True, False], "lsb": True}),
    ("corexy_nonlinear", None, COREXY2),
    ("corexy_measured", None, {"degree": 3, "lsb": True, "fit": "lsq", "split": True}),
])
def test_integer_model_is_the_c_on_the_host(tmp_path, name, unit, cfg):
    p = problem(name) if unit is None else _unit_problem(name, unit)
    im = PolyImpl.fit(p, cfg)
    vec = host_vectors(p)
    assert len(vec) >= 100_000
    r = verify_host(im, tmp_path / "c", vectors=vec)
    assert r["bit_exact"], r


def _unit_problem(name: str, unit: float):
    from nnik.machine.data import build_dataset
    from nnik.implementations.problem import Problem
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(DATASETS / f"{name}.toml")
    return Problem(scn, build_dataset(scn), unit_um=unit)


def test_the_c_clamps_the_dac(tmp_path):
    # the workspace reaches the edge of the head's optical range (+/-32767 codes) and a straight
    # line overshoots there: the outputs run into the DAC's code range
    text = (DATASETS / "galvo_dual_xy2.toml").read_text().replace("[-60.0, 60.0]", "[-72.78, 72.78]")
    p = problem_from(write_toml(tmp_path, text))
    im = PolyImpl.fit(p, {"degree": 1})
    lo_code, hi_code = p.code_range
    r = im.run(p.check[0])
    assert r.pre.max() > hi_code + 1 and r.out.max() == hi_code and r.out.min() == lo_code
    assert verify_host(im, tmp_path / "c", vectors=host_vectors(p, n=20_000))["bit_exact"]
    # the fast paths clamp in their own code (AVR: in the assembly); corners are where it bites
    corners = np.array([[a, b] for a in (p.lo[0], p.hi[0], 0) for b in (p.lo[1], p.hi[1], 0)], dtype=np.int64)
    vec = np.concatenate([np.random.default_rng(5).integers(p.lo, p.hi + 1, (40, 2)), corners])
    assert (im.run(vec).out == hi_code).any()
    for target, tool in (("avr", "simavr"), ("pic18", "gpsim")):
        require_tool(tool)
        res = verify_on_target(im, target, tmp_path / "c", tmp_path / target, vectors=vec)
        assert res["bit_exact"], res


@pytest.mark.parametrize("name, cfg, bound", [
    ("galvo_cba2012", {"degree": 3}, 0.08),  # measured 0.069 microstep
    ("galvo_cba2012", CBA5, 0.0085),  # measured 0.0069
    ("galvo_dual_xy2", DUAL5, 0.9),  # measured 0.836 LSB (16-bit DAC, 0.25 um inputs)
    ("corexy_nonlinear", COREXY2, 0.2),  # measured 0.183 microstep
    ("hbot_unicamp", {"degree": 1, "lsb": True}, 0.01),  # affine: exact to 0.000
])
def test_accuracy_does_not_regress(name, cfg, bound):
    a = accuracy(PolyImpl.fit(problem(name), cfg))
    assert a["points"] >= 1001 * 1001
    assert a["pre_max"] < bound


@pytest.mark.parametrize("target, tool, name, cfg", [
    ("avr", "simavr", "galvo_cba2012", CBA5),
    ("pic18", "gpsim", "corexy_nonlinear", COREXY2),
])
def test_bit_exact_on_the_simulated_chips(tmp_path, target, tool, name, cfg):
    require_tool(tool)
    im = PolyImpl.fit(problem(name), cfg)
    for portable in (False, True):
        r = verify_on_target(im, target, tmp_path / "c", tmp_path / f"b{int(portable)}", portable=portable, n_inside=60)
        assert r["mismatches"] == 0 and r["bit_exact"], r
        assert r["path"] == ("portable" if portable else "fast")
    fast = verify_on_target(im, target, tmp_path / "c", tmp_path / "b0", n_inside=60)
    slow = verify_on_target(im, target, tmp_path / "c", tmp_path / "b1", portable=True, n_inside=60)
    assert fast["cycles"] * 1.5 < slow["cycles"]  # the hardware-multiply path pays


def test_calibration_matches_the_emitted_c():
    from nnik.implementations.poly import cost as poly_cost
    from nnik.implementations.poly.family import PolyImpl

    cal = json.loads(poly_cost.CALIBRATION.read_text())
    assert cal["key"] == poly_cost.reference_key(PolyImpl), "poly C changed: run python -m nnik.implementations.poly.calibrate"
    im = PolyImpl.fit(problem("galvo_cba2012"), CBA5)
    for t in ("avr", "pic18"):
        e = im.estimate(t)
        # the recorded band, where one was measured on this target (nnik.implementations.cost_band)
        assert {"cycles", "flash_bytes", "ram_bytes", "validated"} <= set(e) <= {
            "cycles", "flash_bytes", "ram_bytes", "validated", "cycles_error_pct"}
        assert e["validated"] == cal["validated"]
        ref = cal["reference"][1][t]  # the same configuration, measured at calibration time
        assert abs(e["cycles"] - ref["cycles"]) < 0.03 * ref["cycles"]


def test_a_dac_clamp_written_in_c_is_counted_and_priced(tmp_path):
    """An off-axis 16-bit DAC gimbal: its outputs' offsets put the DAC range outside int16, so the
    clamp is C after the assembly (avr.py, p18.py). The cost model counts those clamps
    (c_clamps) and prices them, within the recorded band on simavr, on a configuration that
    neither the calibration's references nor its validation set hold."""
    from nnik.implementations.poly import cost as poly_cost
    from nnik.implementations.cost_band import stated_band

    require_tool("simavr")
    p = problem_from(poly_cost.REFERENCE_MACHINES / "poly_ref_offaxis_dac16.toml")
    im = PolyImpl.fit(p, {"degree": 3, "coef_bits": 32})
    src = im.render_source()  # one source, every target's path
    avr_part = src[src.index("#if defined(NNIK_KERNEL_AVR)"):src.index("#elif")]
    n = poly_cost.counts(im, "avr")["c_clamps"]
    assert n >= 1 and avr_part.count("    if (out[") == n
    e = im.estimate("avr")
    r = verify_on_target(im, "avr", tmp_path / "c", tmp_path / "avr", n_inside=40)
    assert r["bit_exact"]
    band = stated_band(json.loads(poly_cost.CALIBRATION.read_text()), "avr")
    assert abs(e["cycles"] - r["cycles"]) <= band / 100 * r["cycles"], (e, r["cycles"])
