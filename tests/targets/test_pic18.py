"""PIC18F452 target runner (SDCC pic16 + gputils + gpsim).

Skips when the PIC18 toolchain is missing (see scripts/install_toolchains.sh),
unless NNIK_REQUIRE_TOOLCHAINS=1 (then fails).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nnik.targets import TargetError, run_on_target
from tests.targets.runner_helpers import galvo_reference, need_toolchain, toy_reference, toy_vectors

FIX = Path(__file__).parent / "fixtures"
TARGET = "pic18"
# DOMAIN.md, "Published timings": float galvo IK, SDCC 4.2, gpsim (instruction cycles)
GALVO_REF_CYCLES = 47389




@pytest.fixture(scope="module")
def toy_run(tmp_path_factory):
    need_toolchain(TARGET)
    vec = toy_vectors()
    # batch_size 64 so that the multi-batch path (two gpsim sessions) is exercised too
    res = run_on_target(target=TARGET, sources=[FIX / "toy.c"], include_dirs=[FIX], name="toy",
                        vectors=vec, workdir=tmp_path_factory.mktemp("pic18_toy"),
                        batch_size=64)
    return vec, res


def test_toy_outputs_match_python(toy_run):
    """Also checks that SDCC's >> on negative int32 is arithmetic (as in numpy)."""
    vec, res = toy_run
    out, flags = toy_reference(vec)
    assert res["outputs"].shape == (len(vec), 2)
    np.testing.assert_array_equal(res["outputs"], out)
    np.testing.assert_array_equal(res["flags"], flags)
    assert flags.sum() > 0 and (flags == 0).sum() > 0


def test_toy_cycles_and_sizes(toy_run):
    vec, res = toy_run
    cyc = res["cycles"]
    assert cyc.shape == (len(vec),)
    assert 50 < cyc.min() <= cyc.max() < 5000
    assert res["cycles_mean"] == pytest.approx(cyc.mean())
    assert res["cycles_max"] == cyc.max()
    assert res["flash_bytes"] > 0 and res["ram_bytes"] > 0
    assert 0 < res["model_flash_bytes"] < res["flash_bytes"]
    assert res["model_ram_bytes"] >= 0
    assert res["clock_hz"] == 16_000_000 and res["cycle_hz"] == 4_000_000
    assert res["target"] == "pic18"
    assert "pic16" in res["compiler"]
    assert "-p18f452" in res["compiler_flags"]


def test_long_calls_are_linear(tmp_path):
    need_toolchain(TARGET)
    # equal spacing in multiples of 256 so that data-dependent 16-bit compare/carry paths
    # contribute the same amount per step
    n = np.array([[1024 + 10240 * k, 0] for k in range(4)], dtype=np.int64)
    res = run_on_target(target=TARGET, sources=[FIX / "spin.c"], name="spin", vectors=n,
                        workdir=tmp_path)
    c = res["cycles"]
    assert c.max() > 65536
    d = np.diff(c)
    assert (d == d[0]).all(), c
    assert res["outputs"][:, 0].tolist() == n[:, 0].tolist()


def test_float_galvo_cycles_in_published_ballpark(tmp_path, capsys):
    need_toolchain(TARGET)
    rng = np.random.default_rng(3)
    vec = rng.integers(-200000, 200001, size=(24, 2))
    res = run_on_target(target=TARGET, sources=[FIX / "float_galvo.c"], name="galvo",
                        vectors=vec, workdir=tmp_path)
    ref = galvo_reference(vec)
    assert np.abs(res["outputs"] - ref).max() <= 1
    assert (res["flags"] == 0).all()
    mean = res["cycles_mean"]
    with capsys.disabled():
        print(f"\n[pic18] float galvo IK, SDCC pic16: {mean:.0f} instruction cycles mean, max "
              f"{res['cycles_max']} (DOMAIN.md: {GALVO_REF_CYCLES}); model "
              f"{res['model_flash_bytes']} B flash")
    assert 0.5 * GALVO_REF_CYCLES < mean < 2.0 * GALVO_REF_CYCLES


def test_build_error_raises_target_error(tmp_path):
    need_toolchain(TARGET)
    with pytest.raises(TargetError) as ei:
        run_on_target(target=TARGET, sources=[FIX / "broken.c"], name="broken",
                      vectors=np.zeros((1, 2), dtype=np.int64), workdir=tmp_path)
    assert "\n" not in str(ei.value)
