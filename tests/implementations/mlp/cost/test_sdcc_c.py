"""The fast kernel on PIC18 as SDCC runs it (nnik.implementations.mlp.cost.sdcc_c): the counts
follow the emitted C, and the tanh replacements' coefficients are the chip's own (issue 25:
fitted per class and per layer from whole networks, the C path was off by up to 17 %)."""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.bench.mlp_cost import search_check as sc
from nnik.implementations.mlp.cost.calibrations import load_calibration
from nnik.implementations.mlp.cost.fast_features import fast_counts_prefixed, fast_path
from nnik.implementations.mlp.cost.kernels import render_c
from nnik.implementations.mlp.cost.sdcc_c import tanh_coefs
from nnik.implementations.mlp.cost.synthetic import synthetic_model
from nnik.implementations.mlp.cost.trace import tanh_classes

MAC = re.compile(r"nnik_m(?:acu|subu)\(\w+, [\w\[\]]+, (\d+)u\)")


def _portable_body(im) -> str:
    text = render_c(im, kernel="fast")[f"{im.name}.c"]
    return text[text.rindex("#else"):]  # the value code SDCC builds (the last branch)


@settings(max_examples=12, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10**6))
def test_sdcc_counts_follow_the_emitted_c(seed):
    sp = sc.draw_specs(1, seed, tanhs=tuple(t for t in sc.TANHS if t))[0]  # a tanh replacement: the C path
    im = synthetic_model(sp, kernel="fast")
    assert fast_path(im, "pic18") == "c"
    c = fast_counts_prefixed(im, False, "pic18")
    body = _portable_body(im)
    ws = [int(w) for w in MAC.findall(body)]
    looped = "for (i = 0;" in body
    if not looped:
        assert c["c:mac"] == len(ws)
        assert c.get("c:mac_one", 0) == sum(w == 1 for w in ws)
    calls = body.count(f"{im.name}_tanh(")
    if not looped:
        assert c[f"c:tanh[{im.tanh_variant}]"] == calls
    assert not any(k.startswith("c:mac_first") or "weights_w8" in k or "affine_mul" in k for k in c)


def test_tanh_coefficients_from_the_measured_classes():
    names = tanh_classes("lerp32")
    bench = {"lerp32": {n: 100.0 + 10 * i for i, n in enumerate(names)}, "paper_lsq5": {"s0+": 5.0}}
    co = tanh_coefs(bench)
    assert co["c:tanh[lerp32]"] == 100.0
    assert all(co[f"c:tanh_class[lerp32][{n}]"] == 10 * i for i, n in enumerate(names) if i)
    assert not any("paper_lsq5" in k for k in co)  # its first class was not measured: left to the fit


def test_the_calibration_keeps_the_measured_tanh_coefficients():
    kc = load_calibration("pic18-sdcc")["kernels"]["fast"]
    assert kc["tanh_bench"]
    coef = kc["cycles"]["coef"]
    for k, v in tanh_coefs(kc["tanh_bench"]).items():
        assert coef[k] == pytest.approx(v, abs=1e-3), k


@pytest.fixture()
def gpsim():
    from nnik.targets import available

    ok, why = available("pic18")
    if not ok:
        pytest.skip(why)


def test_a_tanh_replacement_costs_on_gpsim_what_the_calibration_says(gpsim, tmp_path):
    from nnik.bench.mlp_cost.tanh_bench import measure_tanh_classes

    stored = load_calibration("pic18-sdcc")["kernels"]["fast"]["tanh_bench"]
    fresh = measure_tanh_classes("pic18-sdcc", ["lerp_mr4"], tmp_path)
    assert fresh["lerp_mr4"] == stored["lerp_mr4"]
    assert fresh["lerp_mr4"]["sat+"] < fresh["lerp_mr4"]["r0+"]  # saturation skips the interpolation
