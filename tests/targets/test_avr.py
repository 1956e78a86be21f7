"""ATmega328P target runner (avr-gcc + simavr).

Skips when the AVR tools are missing, unless NNIK_REQUIRE_TOOLCHAINS=1 (then fails).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nnik.targets import TargetError, run_on_target
from tests.targets.runner_helpers import galvo_reference, need_toolchain, toy_reference, toy_vectors

FIX = Path(__file__).parent / "fixtures"
TARGET = "avr"
# DOMAIN.md, "Published timings": float galvo IK, avr-gcc -Os, simavr
GALVO_REF_CYCLES = 7623




@pytest.fixture(scope="module", params=["-Os", "-O2"])
def toy_run(request, tmp_path_factory):
    need_toolchain(TARGET)
    vec = toy_vectors()
    res = run_on_target(target=TARGET, sources=[FIX / "toy.c"], include_dirs=[FIX], name="toy",
                        vectors=vec, opt=request.param,
                        workdir=tmp_path_factory.mktemp("avr_toy"))
    return vec, res


def test_toy_outputs_match_python(toy_run):
    vec, res = toy_run
    out, flags = toy_reference(vec)
    assert res["outputs"].shape == (len(vec), 2)
    np.testing.assert_array_equal(res["outputs"], out)
    np.testing.assert_array_equal(res["flags"], flags)
    assert flags.sum() > 0 and (flags == 0).sum() > 0  # both branches exercised


def test_toy_cycles_and_sizes(toy_run):
    vec, res = toy_run
    cyc = res["cycles"]
    assert cyc.shape == (len(vec),)
    # 32-bit clamp + multiply + shift on an 8-bit core: tens to a few hundred cycles
    assert 20 < cyc.min() <= cyc.max() < 2000
    assert res["cycles_mean"] == pytest.approx(cyc.mean())
    assert res["cycles_max"] == cyc.max()
    assert res["flash_bytes"] > 0 and res["ram_bytes"] > 0
    assert 0 < res["model_flash_bytes"] < res["flash_bytes"]
    assert res["model_ram_bytes"] >= 0
    assert res["clock_hz"] == 16_000_000
    assert res["target"] == "avr"
    assert "avr-gcc" in res["compiler"]
    assert "-mmcu=atmega328p" in res["compiler_flags"]


def test_long_calls_count_timer_overflows(tmp_path):
    """Cycles stay exactly linear across Timer1 overflows (calls > 65535 cycles)."""
    need_toolchain(TARGET)
    # equal spacing in multiples of 256 so that data-dependent 16-bit compare/carry paths
    # contribute the same amount per step
    n = np.array([[1024 + 10240 * k, 0] for k in range(5)], dtype=np.int64)
    res = run_on_target(target=TARGET, sources=[FIX / "spin.c"], name="spin", vectors=n,
                        opt="-Os", workdir=tmp_path)
    c = res["cycles"]
    assert c.max() > 3 * 65536  # several overflows
    d = np.diff(c)
    assert (d == d[0]).all(), c
    assert res["outputs"][:, 0].tolist() == n[:, 0].tolist()


def test_float_galvo_cycles_in_published_ballpark(tmp_path, capsys):
    need_toolchain(TARGET)
    rng = np.random.default_rng(3)
    vec = rng.integers(-200000, 200001, size=(24, 2))
    res = run_on_target(target=TARGET, sources=[FIX / "float_galvo.c"], name="galvo",
                        vectors=vec, opt="-Os", workdir=tmp_path)
    ref = galvo_reference(vec)
    assert np.abs(res["outputs"] - ref).max() <= 1  # float32 vs float64 rounding
    assert (res["flags"] == 0).all()
    mean = res["cycles_mean"]
    with capsys.disabled():
        print(f"\n[avr] float galvo IK, avr-gcc -Os: {mean:.0f} cycles mean, max {res['cycles_max']}"
              f" (DOMAIN.md: {GALVO_REF_CYCLES}); model {res['model_flash_bytes']} B flash")
    assert 0.5 * GALVO_REF_CYCLES < mean < 2.0 * GALVO_REF_CYCLES


def test_build_error_raises_target_error(tmp_path):
    need_toolchain(TARGET)
    with pytest.raises(TargetError) as ei:
        run_on_target(target=TARGET, sources=[FIX / "broken.c"], name="broken",
                      vectors=np.zeros((1, 2), dtype=np.int64), workdir=tmp_path)
    msg = str(ei.value)
    assert "\n" not in msg and "broken.c" in msg
