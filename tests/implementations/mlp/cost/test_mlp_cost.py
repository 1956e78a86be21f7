"""The static cycle/flash/RAM estimator (nnik.implementations.mlp.cost).

Most tests need no simulator: the calibration is package data and the networks are built from
random weights with the real quantiser. One test runs a held-out network on simavr.
"""

from __future__ import annotations

import itertools
import json
import os
import shutil

import numpy as np
import pytest

from nnik.errors import NnikError
from nnik.implementations.mlp.cost import calibrations, kernels, predict, synthetic, trace, validity

BUILTIN = ("avr-gcc-Os", "avr-gcc-O2", "pic18-sdcc")


def _net(hidden, tanh="lerp_mr4", seed=3, kernel=None, scenario="galvo"):
    spec = synthetic.CalSpec(scenario, tuple(hidden), tanh=tanh, seed=seed, gain=1.5)
    return synthetic.synthetic_model(spec, kernel=kernel)


@pytest.fixture(scope="module")
def nets():
    return {h: _net(h) for h in [(4,), (6,), (8,), (12,), (16,), (8, 8), (9,)]}


def test_calibration_files_load_and_cover_every_profile():
    names = calibrations.profiles()
    for p in BUILTIN:
        assert p in names
        cal = calibrations.load_calibration(p)
        assert cal["profile"] == p and cal["target"] == calibrations.BUILTIN_PROFILES[p]["target"]
        for key in ("compiler", "flags", "date", "command", "validity", "shift_tables", "kernels"):
            assert key in cal, (p, key)
        assert cal["command"].startswith("python3 -m nnik.bench.mlp_cost calibrate --target ")
        assert cal["validated"] is True
        for kkey, kc in cal["kernels"].items():
            for what in ("cycles", "flash", "ram"):
                assert kc[what]["coef"], (p, kkey, what)
            # every structural calibration network stays outside the judged hidden sizes 4..16; the
            # fast kernel's search-space draws (random weights, not the sweep's trained networks) do not
            drawn = {sp.label for sp in synthetic.search_calibration_specs(cal["target"])} if kkey == "fast" else set()
            for m in kc["models"]:
                assert m["spec"] in drawn or not any(4 <= h <= 16 for h in m["shape"][1:-1]), m["spec"]
        portable = cal["kernels"].get("portable") or cal["kernels"].get(calibrations.DEFAULT_KERNEL_KEY)
        assert portable is not None
        from nnik.implementations.mlp import tanh as activations

        for v in activations.VARIANTS:
            assert f"tanh[{v}]" in portable["cycles"]["coef"], (p, v)
    assert set(calibrations.profiles("avr")) >= {"avr-gcc-Os", "avr-gcc-O2"}
    assert "pic18-sdcc" in calibrations.profiles("pic18")


def test_estimate_keys_and_units(nets):
    im = nets[(8,)]
    for target in calibrations.TARGETS:
        e = predict.estimate(im, target)
        for k in ("cycles", "us", "flash_bytes", "ram_bytes", "profile", "validated", "breakdown"):
            assert k in e
        assert e["profile"] == calibrations.DEFAULT_PROFILE[target]
        assert e["cycles"] > 0 and e["flash_bytes"] > 0 and e["ram_bytes"] >= 0
        assert isinstance(e["validated"], bool)
        assert sum(e["breakdown"].values()) == pytest.approx(e["cycles"], abs=1.0)
        cpc = calibrations.CLOCKS_PER_CYCLE[target]
        assert e["us"] == pytest.approx(e["cycles"] * cpc / 16e6 * 1e6)
        e8 = predict.estimate(im, target, clock_hz=8_000_000)
        assert e8["us"] == pytest.approx(2 * e["us"])


def test_estimate_grows_with_hidden_size_and_a_second_layer(nets):
    for prof in BUILTIN:
        target = calibrations.BUILTIN_PROFILES[prof]["target"]
        cyc = [predict.estimate(nets[(h,)], target, prof)["cycles"] for h in (4, 6, 8, 12, 16)]
        assert all(b > a for a, b in itertools.pairwise(cyc)), (prof, cyc)
        fl = [predict.estimate(nets[(h,)], target, prof)["flash_bytes"] for h in (4, 6, 8, 12, 16)]
        assert all(b > a for a, b in itertools.pairwise(fl)), (prof, fl)
        two = predict.estimate(nets[(8, 8)], target, prof)
        one = predict.estimate(nets[(8,)], target, prof)
        assert two["cycles"] > one["cycles"] and two["flash_bytes"] > one["flash_bytes"]


def test_flash_grows_by_about_two_bytes_per_int16_weight(nets):
    a, b = nets[(8,)], nets[(9,)]
    # one more neuron: n_in + n_out int16 weights and one int32 bias
    added_weights = (a.shape[0] + a.shape[-1])
    for prof in BUILTIN:
        target = calibrations.BUILTIN_PROFILES[prof]["target"]
        d = predict.estimate(b, target, prof)["flash_bytes"] - predict.estimate(a, target, prof)["flash_bytes"]
        assert d == pytest.approx(2 * added_weights + 4, abs=3), (prof, d)
        kc = calibrations.load_calibration(prof)["kernels"]
        portable = kc.get("portable") or kc[calibrations.DEFAULT_KERNEL_KEY]
        assert portable["flash"]["coef"]["table_bytes"] == pytest.approx(1.0, abs=0.1)


def test_unknown_target_or_profile_is_a_clear_nnik_error(nets):
    im = nets[(4,)]
    with pytest.raises(NnikError, match=r"unknown target 'arm'.*avr, pic18"):
        predict.estimate(im, "arm")
    with pytest.raises(NnikError, match=r"unknown profile 'O3' for target 'avr'.*avr-gcc-Os"):
        predict.estimate(im, "avr", "O3")
    with pytest.raises(NnikError, match=r"unknown profile 'sdcc' for target 'avr'"):
        predict.estimate(im, "avr", "sdcc")
    with pytest.raises(NnikError, match="clock_hz"):
        predict.estimate(im, "avr", clock_hz=0)


def test_profile_spellings():
    assert calibrations.resolve_profile("avr", None) == "avr-gcc-Os"
    assert calibrations.resolve_profile("avr", "O2") == "avr-gcc-O2"
    assert calibrations.resolve_profile("avr", "-O2") == "avr-gcc-O2"
    assert calibrations.resolve_profile("avr", "avr-gcc-Os") == "avr-gcc-Os"
    assert calibrations.resolve_profile("pic18", "sdcc") == "pic18-sdcc"


def test_feature_trace_matches_the_integer_model(nets):
    """The estimator's own walk through the data path ends where IntegerModel's does."""
    im = nets[(8, 8)]
    pts = trace.typical_inputs(im, n=300)
    h, _, _ = im.forward_hidden(pts)
    tr = trace.hidden_trace(im, pts)
    assert np.array_equal(tr.h, h)


def test_calibration_networks_avoid_the_judged_sizes():
    for kern in kernels.kernel_options():
        for sp in synthetic.calibration_specs(kern):
            assert not any(4 <= h <= 16 for h in sp.hidden), sp.label


def test_validated_flag_and_notes(nets):
    e = predict.estimate(nets[(8,)], "avr")
    cal = calibrations.load_calibration("avr-gcc-Os")
    kc = cal["kernels"][kernels.kernel_key(kernels.model_kernel(nets[(8,)]))]
    if e["validated"]:  # only with an unchanged generator and a recorded, passing sweep
        assert kc["reference_c_hash"] == validity.reference_c_hash(kc["kernel"])
        assert any("recorded sweep" in n for n in e["notes"])
    else:
        assert e["notes"]
    deep = _net((5, 5, 5))
    e3 = predict.estimate(deep, "avr")
    assert e3["validated"] is False and any("two hidden layers" in n for n in e3["notes"])


def _require_avr():
    if shutil.which("avr-gcc") is None or shutil.which("simavr") is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("avr-gcc/simavr not found but NNIK_REQUIRE_TOOLCHAINS=1")
        pytest.skip("avr toolchain not installed (run `make toolchains`)")


def test_held_out_2_10_2_within_3_percent_on_avr_os(tmp_path):
    """A network the calibration never saw (hidden size 10), measured on simavr."""
    _require_avr()
    from nnik.targets import run_on_target

    im = _net((10,), seed=11)
    csrc = kernels.write_c(im, tmp_path / "c")
    vec = synthetic.in_domain_vectors(im, 60, seed=5)
    r = run_on_target("avr", [csrc], [csrc.parent], im.name, vec, opt="-Os", workdir=tmp_path / "w", progress=False)
    e = predict.estimate(im, "avr", "avr-gcc-Os")
    err = abs(e["cycles"] - r["cycles_mean"]) / r["cycles_mean"]
    assert err <= 0.03, (e["cycles"], r["cycles_mean"])
    assert abs(e["flash_bytes"] - r["model_flash_bytes"]) / r["model_flash_bytes"] <= 0.05
    assert json.dumps(e)  # plain JSON types


def test_calibration_matches_the_current_generator():
    """The stored calibration was measured on the C the generator emits today: the C of the
    reference models (plus runtime headers, harnesses, shift benchmark) hashes as it did then.
    A refactor that emits the same C passes; a change in the C needs
    `python3 -m nnik.bench.mlp_cost calibrate --target avr|pic18` (and a sweep --record)."""
    for kernel in ("portable", "fast"):
        for profile in BUILTIN:
            cal = json.loads((calibrations.CAL_DIR / f"{profile}.json").read_text())
            assert validity.stored_hash(cal, kernel) == validity.reference_c_hash(kernel), (profile, kernel)


def test_reference_hash_is_the_emitted_c_and_nothing_else(monkeypatch):
    """The key follows the C text: one changed character of a model's C changes it, the same
    C from other code (another dict order, another function) keeps it."""
    fresh = validity.reference_c_hash.__wrapped__
    want = {k: fresh(k) for k in ("portable", "fast")}
    assert want["portable"] != want["fast"]
    real = validity.render_c

    def same_c_other_code(im, source, kernel=None):
        return dict(reversed(list(real(im, source, kernel=kernel).items())))

    monkeypatch.setattr(validity, "render_c", same_c_other_code)
    assert {k: fresh(k) for k in want} == want

    def one_more_space(im, source, kernel=None):
        return {f: (t.replace("return", "return ", 1) if f.endswith(".c") else t)
                for f, t in real(im, source, kernel=kernel).items()}

    monkeypatch.setattr(validity, "render_c", one_more_space)
    for k in want:
        assert fresh(k) != want[k], k


def test_reference_hash_covers_the_included_runtime_headers_only(monkeypatch, tmp_path):
    shutil.copytree(calibrations.REPO_ROOT / "codegen", tmp_path / "codegen")
    monkeypatch.setattr(validity, "REPO_ROOT", tmp_path)
    fresh = validity.reference_c_hash.__wrapped__
    assert fresh("portable") == validity.reference_c_hash("portable")
    (tmp_path / "codegen" / "runtime" / "nnik_new_family.h").write_text("/* no model includes it */\n")
    assert fresh("portable") == validity.reference_c_hash("portable")
    hdr = tmp_path / "codegen" / "runtime" / "nnik_flash.h"
    hdr.write_text(hdr.read_text() + "\n")
    assert fresh("portable") != validity.reference_c_hash("portable")


def test_a_changed_c_marks_estimates_unvalidated(nets, monkeypatch):
    monkeypatch.setattr(predict, "reference_c_hash", lambda kernel=None: "0" * 16)
    e = predict.estimate(nets[(8,)], "avr")
    assert e["validated"] is False
    assert any("emitted C changed" in n for n in e["notes"])
