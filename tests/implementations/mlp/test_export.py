"""The generated C: compiles cleanly everywhere and matches the integer model bit for bit."""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import pytest

from nnik.implementations.mlp import quantize as fx
from nnik import pipeline
from nnik.machine.data import Dataset
from nnik.emit.templating import write_sources
from nnik.implementations.mlp.export import render_model_c
from nnik.implementations.mlp.train import TrainedModel
from nnik.implementations.mlp.host import run_host, verification_inputs, verify_host
from tests.conftest import require_tool


def test_host_bit_exact_galvo(galvo_fixed):
    h = galvo_fixed["host"]
    assert h["bit_exact"] and h["mismatches"] == 0
    assert h["points"] >= 100_000
    assert all(v == 0 for v in h["overflows"].values())
    assert all(v == 0 for k, v in h["saturations"].items() if k != "outside")


def test_host_bit_exact_corexy_residual(corexy_fixed):
    h = corexy_fixed["host"]
    assert h["bit_exact"] and h["mismatches"] == 0 and h["points"] >= 100_000
    assert all(v == 0 for v in h["overflows"].values())


def test_header_contract(galvo_fixed, galvo_run):
    h = (galvo_run / pipeline.MLP_DIR / "galvo_cba2012.h").read_text()
    for needle in ("#define GALVO_CBA2012_N_IN  2", "#define GALVO_CBA2012_N_OUT 2",
                   "int8_t galvo_cba2012_ik(const int32_t in_um[GALVO_CBA2012_N_IN], int32_t out[GALVO_CBA2012_N_OUT]);",
                   "GALVO_CBA2012_IN0_MIN_UM (-100000L)", "GALVO_CBA2012_IN1_MAX_UM (100000L)",
                   galvo_fixed["fixed"]["model_hash"], '"2-6-2"', '"microstep"', "#ifndef GALVO_CBA2012_H"):
        assert needle in h, needle
    c = (galvo_run / pipeline.MLP_DIR / "galvo_cba2012.c").read_text()
    for banned in ("float", "double", "malloc", "int64_t a", "#include <math.h>"):
        assert banned not in c.split("#ifdef NNIK_INSTRUMENT")[0] or banned == "int64_t a", banned
    assert "NNIK_FLASH" in c


def test_a_corrupted_table_is_caught(galvo_fixed, galvo_run, tmp_path):
    """The check can fail: change one weight in the C and the comparison must see it."""
    model = TrainedModel.load(galvo_run / "model.pt")
    ds = Dataset.load(galvo_run / "data.npz")
    im = fx.quantize(model, calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]))
    files = render_model_c(im, "test")
    w = im.hidden[0].W.ravel()
    src = files["galvo_cba2012.c"]
    first_row = ", ".join(str(int(v)) for v in w[:2])
    assert first_row in src
    files["galvo_cba2012.c"] = src.replace(first_row, ", ".join([str(int(w[0]) + 1)] + [str(int(v)) for v in w[1:2]]), 1)
    write_sources(files, tmp_path)
    res = verify_host(im, tmp_path, {"test": verification_inputs(im, ds.p["test"][:3000])["test"]})
    assert res["mismatches"] > 0


def test_int8_build_is_bit_exact(galvo_run, tmp_path):
    model = TrainedModel.load(galvo_run / "model.pt")
    im = fx.quantize(model, weight_bits=8)
    write_sources(render_model_c(im, "test"), tmp_path)
    pts = np.random.default_rng(5).integers(im.inp.lo - 1000, im.inp.hi + 1000, (5000, 2))
    c = run_host(tmp_path, im.name, pts)
    total, out, flags = im.run(pts)
    np.testing.assert_array_equal(c["out"], out)
    np.testing.assert_array_equal(c["total"], total)
    np.testing.assert_array_equal(c["flags"], flags)
    assert "int8_t" in (tmp_path / "galvo_cba2012.c").read_text()


@pytest.mark.parametrize("opt", ["-Os", "-O2"])
def test_compiles_warning_free_with_avr_gcc(galvo_fixed, corexy_fixed, galvo_run, corexy_run, tmp_path, opt):
    require_tool("avr-gcc")
    for run, name in ((galvo_run, "galvo_cba2012"), (corexy_run, "corexy_nonlinear")):
        r = subprocess.run(["avr-gcc", "-mmcu=atmega328p", opt, "-std=c99", "-Wall", "-Wextra", "-Werror", "-c",
                            str(run / pipeline.MLP_DIR / f"{name}.c"), "-I", str(run / pipeline.MLP_DIR), "-o", str(tmp_path / f"{name}.o")],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr


def test_float_ik_exported_and_checked(galvo_fixed, corexy_fixed):
    g = galvo_fixed["baselines"]
    assert g["float"]["available"] and max(g["float"]["max_abs"]) <= 0.51  # libm float32 + rounding
    for m in (galvo_fixed, corexy_fixed):
        assert set(m["baselines"]) == {"float"}  # the old LUT baseline retired: a table is the lut family's
    c = corexy_fixed["baselines"]
    assert not c["float"]["available"] and "closed-form" in c["float"]["reason"].replace("closed form", "closed-form")


# ---- the fast kernel: same C API, bit-exact on the host in both C paths ---------------------------
def _fast_c(run_dir, tmp_path):
    model = TrainedModel.load(run_dir / "model.pt")
    ds = Dataset.load(run_dir / "data.npz")
    im = fx.quantize(model, calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]), kernel="fast")
    files = render_model_c(im, "test")
    write_sources(files, tmp_path)
    return im, ds, files


@pytest.mark.parametrize("which", ["galvo", "corexy"])
def test_fast_kernel_host_bit_exact(galvo_run, corexy_run, tmp_path, which):
    """Instrumented (int64 accumulators, overflow counters) and plain (uint32 accumulators)
    C, both with UBSan+ASan, against the integer model on >= 100k points."""
    from nnik.targets.host import run_host_driver

    im, ds, _ = _fast_c(galvo_run if which == "galvo" else corexy_run, tmp_path)
    inputs = verification_inputs(im, ds.p["test"])
    res = verify_host(im, tmp_path, inputs)
    assert res["bit_exact"] and res["mismatches"] == 0 and res["points"] >= 100_000
    assert all(v == 0 for v in res["overflows"].values())
    assert all(v == 0 for k, v in res["saturations"].items() if k != "outside")
    pts = np.concatenate(list(inputs.values()))
    c = run_host_driver(tmp_path, im.name, pts)
    _, out, flags = im.run(pts)
    np.testing.assert_array_equal(c["out"], out)
    np.testing.assert_array_equal(c["flags"], flags)


def test_fast_kernel_header_and_source_contract(galvo_run, tmp_path):
    im, _, files = _fast_c(galvo_run, tmp_path)
    h = files["galvo_cba2012.h"]
    assert ("int8_t galvo_cba2012_ik(const int32_t in_um[GALVO_CBA2012_N_IN], int32_t out[GALVO_CBA2012_N_OUT]);"
            in h)
    assert im.model_hash() in h and "NNIK_INSTRUMENT" in h
    c = files["galvo_cba2012.c"]
    for banned in ("float", "double", "malloc", "#include <math.h>"):
        assert banned not in c.split("#ifdef NNIK_INSTRUMENT")[0], banned
    assert "NNIK_FLASH const uint16_t galvo_cba2012_tanh_q1_14_s8[257]" in c
    for path in ("NNIK_KERNEL_AVR", "NNIK_KERNEL_P18", "nnik_macu("):  # asm for both chips, C fallback
        assert path in c, path
    assert (tmp_path / "nnik_kernel.h").is_file() and (tmp_path / "nnik_flash.h").is_file()


def test_fast_kernel_corrupted_constant_is_caught(galvo_run, tmp_path):
    """A weight constant changed in the C (its portable path) must show up on the host."""
    im, ds, files = _fast_c(galvo_run, tmp_path)
    src = files["galvo_cba2012.c"]
    w = abs(int(im.hidden[0].W[0, 0]))
    needle = f", x0, {w}u);"
    assert needle in src
    files["galvo_cba2012.c"] = src.replace(needle, f", x0, {w + 1}u);", 1)
    write_sources(files, tmp_path)
    res = verify_host(im, tmp_path, {"test": verification_inputs(im, ds.p["test"][:3000])["test"]})
    assert res["mismatches"] > 0


def test_render_refuses_a_kernel_the_model_was_not_quantised_for(galvo_run):
    from nnik.errors import NnikError

    model = TrainedModel.load(galvo_run / "model.pt")
    with pytest.raises(NnikError, match="quantised for kernel 'portable'"):
        render_model_c(fx.quantize(model), "test", kernel="fast")


@pytest.mark.parametrize("opt", ["-Os", "-O2"])
def test_fast_kernel_compiles_warning_free(galvo_run, corexy_run, tmp_path, opt):
    """avr-gcc (the assembly path and -DNNIK_PORTABLE) and host gcc -pedantic, -Werror."""
    for run in (galvo_run, corexy_run):
        im, _, _ = _fast_c(run, tmp_path)
        src = str(tmp_path / f"{im.name}.c")
        builds = [["gcc", opt, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-c", src]]
        if shutil.which("avr-gcc"):
            for extra in ([], ["-DNNIK_PORTABLE"]):
                builds.append(["avr-gcc", "-mmcu=atmega328p", opt, "-std=c99", "-Wall", "-Wextra", "-Werror",
                               *extra, "-c", src])
        elif os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("avr-gcc not found but NNIK_REQUIRE_TOOLCHAINS=1")
        for cmd in builds:
            r = subprocess.run([*cmd, "-I", str(tmp_path), "-o", str(tmp_path / "x.o")], capture_output=True, text=True,
                               check=False)
            assert r.returncode == 0, (cmd, r.stderr)


def test_fast_kernel_compiles_with_sdcc_pic16(galvo_run, tmp_path):
    from nnik.targets import toolchain

    sdcc = toolchain.find_tool("sdcc")
    if sdcc is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("sdcc (pic16) not found but NNIK_REQUIRE_TOOLCHAINS=1")
        pytest.skip("sdcc with the pic16 port not installed")
    im, _, _ = _fast_c(galvo_run, tmp_path)
    r = subprocess.run([sdcc, "-mpic16", "-p18f452", "--use-non-free", "-c", f"{im.name}.c", "-o", "m.o"],
                       capture_output=True, text=True, cwd=tmp_path, check=False)
    assert r.returncode == 0, r.stderr
    errors = [ln for ln in (r.stdout + r.stderr).splitlines() if "error" in ln.lower() or "warning" in ln.lower()]
    assert not errors, errors
