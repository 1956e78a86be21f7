"""The float math.h IK (the speed reference): its C against its numpy mirror and the exact IK."""

from __future__ import annotations

import os
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from nnik.machine.data import exact_targets
from nnik.machine.domain import clamp_um, domain_um
from nnik.machine.scenario import load_scenario
from nnik.targets import float_ik

ROOT = Path(__file__).resolve().parents[2]
DATASETS = ROOT / "datasets"
RUNTIME = ROOT / "codegen" / "runtime"
DRIVER = ROOT / "codegen" / "harness" / "host" / "ik_driver.c"
HOST_FLAGS = ["-std=c99", "-pedantic", "-O2", "-Wall", "-Wextra", "-Werror",
              "-fsanitize=undefined,address", "-fno-sanitize-recover=all"]
AVR_FLAGS = ["-mmcu=atmega328p", "-Os", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror"]

ANALYTIC = ["galvo_cba2012", "galvo_dual_xy2", "hbot_unicamp", "corexy_nonlinear"]
FLOAT_OK = ["galvo_cba2012", "galvo_dual_xy2", "hbot_unicamp"]
ALL = ANALYTIC + ["corexy_measured"]


@lru_cache(maxsize=None)
def scenario(name):
    return load_scenario(DATASETS / f"{name}.toml")



def truth_units(scn, in_um):
    """Exact IK (float64 units) at the clamped integer inputs, clipped to the DAC codes."""
    c, _ = clamp_um(in_um, scn.workspace)
    q = exact_targets(scn, c / 1000.0)
    if scn.actuator.code_range is not None:
        q = np.clip(q, *scn.actuator.code_range)
    return q


def probe_inputs(scn, n_random=17000, seed=7):
    """~20,000 int64 inputs (um): uniform in the domain, corners, edges, and points outside the
    domain up to the int32 limits."""
    rng = np.random.default_rng(seed)
    lo, hi = domain_um(scn.workspace)
    pts = [np.stack([rng.integers(lo[a], hi[a] + 1, n_random) for a in range(2)], 1)]
    special = [np.array([lo[a], lo[a] + 1, hi[a] - 1, hi[a], (lo[a] + hi[a]) // 2]) for a in range(2)]
    gx, gy = np.meshgrid(special[0], special[1])
    pts.append(np.stack([gx.ravel(), gy.ravel()], 1))
    # edges: one coordinate on the boundary, the other random
    m = 500
    for a in range(2):
        e = np.stack([rng.integers(lo[b], hi[b] + 1, m) for b in range(2)], 1)
        e[:, a] = np.where(rng.random(m) < 0.5, lo[a], hi[a])
        pts.append(e)
    # outside: just beyond, far beyond, the int32 extremes
    big = np.iinfo(np.int32)
    span = hi - lo
    out = np.stack([rng.integers(lo[a] - 2 * span[a], hi[a] + 2 * span[a] + 1, 2000) for a in range(2)], 1)
    pts.append(out)
    ext = np.array([big.min, big.min + 1, lo[0] - 1, hi[0] + 1, big.max])
    pts.append(np.stack(np.meshgrid(ext, np.array([big.min, lo[1] - 1, lo[1], hi[1], hi[1] + 1, big.max])), -1).reshape(-1, 2))
    pts.append(np.array([[lo[0] - 1, lo[1]], [hi[0] + 1, hi[1]], [lo[0], lo[1] - 1], [hi[0], hi[1] + 1]]))
    return np.concatenate(pts).astype(np.int64)


def compile_host(tmp_path, files: dict[str, str], fn: str, header: str, cc="gcc") -> Path:
    for k, v in files.items():
        (tmp_path / k).write_text(v)
    exe = tmp_path / f"{fn}.exe"
    srcs = [str(tmp_path / k) for k in files if k.endswith(".c")]
    cmd = [cc, *HOST_FLAGS, "-I", str(RUNTIME), "-I", str(tmp_path), f"-DIK_FN={fn}",
           f'-DIK_HEADER="{header}"', "-o", str(exe), str(DRIVER), *srcs, "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    return exe


def run_driver(exe: Path, in_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    text = "\n".join(f"{a} {b}" for a, b in in_um.tolist()) + "\n"
    env = dict(os.environ, UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    res = subprocess.run([str(exe)], input=text, capture_output=True, text=True, env=env)
    assert res.returncode == 0 and not res.stderr.strip(), res.stderr[:2000]
    a = np.array(res.stdout.split(), dtype=np.int64).reshape(-1, 3)
    return a[:, :2], a[:, 2]


def avr_gcc():
    if shutil.which("avr-gcc"):
        return "avr-gcc"
    if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
        pytest.fail("avr-gcc not found and NNIK_REQUIRE_TOOLCHAINS=1")
    pytest.skip("avr-gcc not installed")


needs_gcc = pytest.mark.skipif(shutil.which("gcc") is None, reason="host gcc not installed")


# ---------------------------------------------------------------- float baseline


def test_float_availability():
    for name in FLOAT_OK:
        assert float_ik.float_unavailable_reason(scenario(name)) is None
        files = float_ik.render_float_c(scenario(name))
        assert set(files) == {f"{name}_float.h", f"{name}_float.c"}
        assert f"int8_t {name}_float_ik(const int32_t in_um[{name}_float_N_IN]" in files[f"{name}_float.h"]
        assert f"#define {name}_float_N_OUT 2" in files[f"{name}_float.h"]
    assert float_ik.render_float_c(scenario("corexy_nonlinear")) is None
    assert "no closed-form inverse with nonlinear distortion" in float_ik.float_unavailable_reason(scenario("corexy_nonlinear"))
    assert float_ik.render_float_c(scenario("corexy_measured")) is None
    assert "measured" in float_ik.float_unavailable_reason(scenario("corexy_measured"))


@pytest.mark.parametrize("name", FLOAT_OK)
def test_float_reference_within_one_unit(name):
    scn = scenario(name)
    x = probe_inputs(scn)
    out, flags = float_ik.float_ik_reference(scn, x)
    q = truth_units(scn, x)
    assert np.abs(out - q).max() < 0.5 + 0.05
    np.testing.assert_array_equal(flags, clamp_um(x, scn.workspace)[1])


@needs_gcc
@pytest.mark.parametrize("name", FLOAT_OK)
def test_float_c_within_one_unit_of_exact(name, tmp_path):
    scn = scenario(name)
    exe = compile_host(tmp_path, float_ik.render_float_c(scn), f"{name}_float_ik", f"{name}_float.h")
    x = probe_inputs(scn)
    out, flags = run_driver(exe, x)
    q = truth_units(scn, x)
    err = np.abs(out - q)
    ref, _ = float_ik.float_ik_reference(scn, x)
    print(f"\n{name}: float C vs exact IK, max |out - exact| = {err.max():.4f} {scn.unit} "
          f"(0.5 is the rounding); differs from the float32 reference in {np.count_nonzero(out != ref)} "
          f"of {len(x)} points")
    assert err.max() <= 1.0  # one unit at a rounding boundary
    assert err.max() < 0.5 + 0.05  # in fact float32 is that close
    assert np.abs(out - ref).max() <= 1
    np.testing.assert_array_equal(flags, clamp_um(x, scn.workspace)[1])



# ---------------------------------------------------------------- AVR


def test_compiles_warning_free_with_avr_gcc(tmp_path):
    cc = avr_gcc()
    for name in ALL:
        scn = scenario(name)
        files = float_ik.render_float_c(scn)
        if files is None:
            continue
        for k, v in files.items():
            (tmp_path / k).write_text(v)
        src = tmp_path / f"{name}_float.c"
        res = subprocess.run([cc, *AVR_FLAGS, "-I", str(RUNTIME), "-I", str(tmp_path), "-c", str(src),
                              "-o", str(tmp_path / f"{name}_float.o")], capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
