"""The float and lookup-table baselines: their C against the Python models and the exact IK."""

from __future__ import annotations

import os
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from nnik.targets import float_ik

from nnik.implementations.lut import baseline as lut_baseline
from nnik.machine.data import build_dataset, exact_targets
from nnik.machine.domain import clamp_um, domain_um
from nnik.machine.scenario import load_scenario

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
BUDGETS = [128, 1024]  # ~ the weights of a 2-6-2 MLP, and a generous table


@lru_cache(maxsize=None)
def scenario(name):
    return load_scenario(DATASETS / f"{name}.toml")


@lru_cache(maxsize=None)
def dataset(name):
    return build_dataset(scenario(name))


@lru_cache(maxsize=None)
def lut_for(name, budget):
    scn = scenario(name)
    if scn.mechanism.analytic:
        return lut_baseline.build_lut(scn, budget)
    ds = dataset(name)
    return lut_baseline.build_lut(scn, budget, ds.p["train"], ds.q["train"])


def truth_units(scn, in_um):
    """Exact IK (float64 units) at the clamped integer inputs, clipped to the DAC codes."""
    c, _ = clamp_um(in_um, scn.workspace)
    q = exact_targets(scn, c / 1000.0)
    if scn.actuator.code_range is not None:
        q = np.clip(q, *scn.actuator.code_range)
    return q


def probe_inputs(scn, lut=None, n_random=17000, seed=7):
    """~20,000 int64 inputs (um): uniform in the domain, corners, edges, the cells' boundaries
    (node positions +-1 um), and points outside the domain up to the int32 limits."""
    rng = np.random.default_rng(seed)
    lo, hi = domain_um(scn.workspace)
    pts = [np.stack([rng.integers(lo[a], hi[a] + 1, n_random) for a in range(2)], 1)]
    special = [np.array([lo[a], lo[a] + 1, hi[a] - 1, hi[a], (lo[a] + hi[a]) // 2]) for a in range(2)]
    if lut is not None:
        for a in range(2):
            t = lo[a] + lut.node_um[a]
            nodes = np.concatenate([np.floor(t) + d for d in (-1, 0, 1, 2)]).astype(np.int64)
            special[a] = np.concatenate([special[a], np.clip(nodes, lo[a], hi[a])])
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


# ---------------------------------------------------------------- LUT: integer model


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("budget", BUDGETS)
def test_lut_fits_budget_and_model_is_sane(name, budget):
    scn = scenario(name)
    lut = lut_for(name, budget)
    assert lut.flash_bytes <= budget
    assert lut.flash_bytes == 2 * lut.nx * lut.ny * lut.entry_bits // 8
    assert lut.entry_bits == 16  # every shipped scenario's outputs fit int16 entries
    lo, hi = domain_um(scn.workspace)
    np.testing.assert_array_equal(lut.lo_um, lo)
    np.testing.assert_array_equal(lut.hi_um, hi)
    # the grid covers the domain (never short of it), at most a hair beyond
    for a in range(2):
        end = lut.node_um[a][-1]
        assert hi[a] - lo[a] <= end <= (hi[a] - lo[a]) * (1 + 2e-4) + 1
    x = probe_inputs(scn, lut)
    out, flags, pre = lut_baseline.lut_int(lut, x)
    np.testing.assert_array_equal(flags, clamp_um(x, scn.workspace)[1])
    np.testing.assert_array_equal(out, np.floor(pre + 0.5).astype(np.int64) if lut.code_range is None
                                  else np.clip(np.floor(pre + 0.5), *lut.code_range).astype(np.int64))
    # the pre-rounding value is the float bilinear table up to the Q15 position quantisation
    c, _ = clamp_um(x, scn.workspace)
    lf = lut_baseline.lut_float(lut, c / 1000.0)
    dec = lut.offset + lut.table * 2.0 ** -np.array(lut.k)
    dx = np.abs(np.diff(dec, axis=1)).max()
    dy = np.abs(np.diff(dec, axis=0)).max()
    dxy = np.abs(dec[1:, 1:] - dec[1:, :-1] - dec[:-1, 1:] + dec[:-1, :-1]).max()
    assert np.abs(pre - lf).max() <= (dx + dy + dxy) * 2.0 ** -lut.wbits + 1e-9


def test_lut_nodes_are_exact_ik():
    scn = scenario("galvo_cba2012")
    lut = lut_for("galvo_cba2012", 1024)
    lo = lut.lo_um
    gx, gy = np.meshgrid(lo[0] + lut.node_um[0], lo[1] + lut.node_um[1])
    q = exact_targets(scn, np.stack([gx.ravel(), gy.ravel()], 1) / 1000).reshape(lut.ny, lut.nx, 2)
    np.testing.assert_allclose(lut.values, q)
    dec = lut.offset + lut.table * 2.0 ** -np.array(lut.k)
    assert np.abs(dec - q).max() <= 2.0 ** -max(lut.k) / 2 + 1e-9


def test_lut_int32_entries_when_int16_cannot_hold_the_range(tmp_path):
    """A 20-bit DAC: outputs span ~600,000 LSB, so the table is int32 with narrower weights."""
    text = (DATASETS / "galvo_dual_xy2.toml").read_text().replace("bits = 16", "bits = 20")
    p = tmp_path / "g20.toml"
    p.write_text(text)
    scn = load_scenario(p)
    lut = lut_baseline.build_lut(scn, 512)
    assert lut.entry_bits == 32 and lut.wbits < 15 and lut.flash_bytes <= 512
    if shutil.which("gcc") is None:
        pytest.skip("host gcc not installed")
    exe = compile_host(tmp_path, lut_baseline.render_lut_c(lut, "g20"), "g20_lut_ik", "g20_lut.h")
    x = probe_inputs(scn, lut, n_random=4000)
    out, flags = run_driver(exe, x)
    want, wflags, _ = lut_baseline.lut_int(lut, x)
    assert np.count_nonzero(out != want) == 0
    np.testing.assert_array_equal(flags, wflags)


# ---------------------------------------------------------------- LUT: C bit for bit


@needs_gcc
@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("budget", BUDGETS)
def test_lut_c_matches_python_model_bit_for_bit(name, budget, tmp_path):
    scn = scenario(name)
    lut = lut_for(name, budget)
    exe = compile_host(tmp_path, lut_baseline.render_lut_c(lut), f"{name}_lut_ik", f"{name}_lut.h")
    x = probe_inputs(scn, lut)
    assert len(x) >= 20000
    out, flags = run_driver(exe, x)
    want, wflags, _ = lut_baseline.lut_int(lut, x)
    mismatches = int(np.count_nonzero(np.any(out != want, axis=1)))
    assert mismatches == 0, f"{mismatches} mismatches, first at {x[np.any(out != want, axis=1)][:3]}"
    np.testing.assert_array_equal(flags, wflags)
    np.testing.assert_array_equal(flags, clamp_um(x, scn.workspace)[1])


# ---------------------------------------------------------------- LUT: accuracy (reported)


def _test_truth(name):
    scn, ds = scenario(name), dataset(name)
    x = np.rint(ds.p["test"] * 1000).astype(np.int64)
    q = exact_targets(scn, x / 1000.0) if scn.mechanism.analytic else ds.q["test"]
    return x, q


@pytest.mark.parametrize("name", ALL)
def test_lut_accuracy_reported(name):
    scn = scenario(name)
    x, q = _test_truth(name)
    print()
    res = {}
    for budget in BUDGETS:
        lut = lut_for(name, budget)
        acc = lut_baseline.lut_accuracy(lut, x, q)
        res[budget] = acc
        o, p = acc["out"], acc["pre"]
        print(f"{name} LUT {budget:5d} B ({lut.nx}x{lut.ny}, {lut.flash_bytes} B): "
              f"max {o['max_abs'][0]:.3f} / {o['max_abs'][1]:.3f}, RMS {o['rms'][0]:.3f} / {o['rms'][1]:.3f} "
              f"{scn.unit} (before rounding: max {p['max_abs'][0]:.3f} / {p['max_abs'][1]:.3f})")
    # a bigger table is not worse (before rounding) and never wildly off
    assert max(res[1024]["pre"]["max_abs"]) <= max(res[128]["pre"]["max_abs"]) + 1e-9
    limits = {"galvo_cba2012": 1.0, "galvo_dual_xy2": 20.0, "hbot_unicamp": 1.5,
              "corexy_nonlinear": 1.5, "corexy_measured": 2.0}
    assert max(res[1024]["out"]["max_abs"]) <= limits[name]


def test_measured_lut_beats_affine_on_held_out_rows():
    """The fitted calibration table captures the nonlinear errors an affine fit leaves (22.9 usteps)."""
    from sklearn.linear_model import LinearRegression

    ds = dataset("corexy_measured")
    x, q = _test_truth("corexy_measured")
    aff = LinearRegression().fit(ds.p["train"], ds.q["train"]).predict(ds.p["test"])
    lut_err = lut_baseline.lut_accuracy(lut_for("corexy_measured", 1024), x, q)["out"]["max_abs"]
    assert max(lut_err) < np.abs(aff - q).max() / 5
    assert "cross-validation" in lut_for("corexy_measured", 1024).origin


def test_build_lut_rejects_tiny_budget():
    from nnik.errors import NnikError

    with pytest.raises(NnikError, match="budget"):
        lut_baseline.build_lut(scenario("galvo_cba2012"), 15)


# ---------------------------------------------------------------- AVR


@pytest.mark.parametrize("kind", ["float", "lut"])
def test_compiles_warning_free_with_avr_gcc(kind, tmp_path):
    cc = avr_gcc()
    for name in ALL:
        scn = scenario(name)
        files = float_ik.render_float_c(scn) if kind == "float" else lut_baseline.render_lut_c(lut_for(name, 1024))
        if files is None:
            continue
        for k, v in files.items():
            (tmp_path / k).write_text(v)
        src = tmp_path / f"{name}_{kind}.c"
        res = subprocess.run([cc, *AVR_FLAGS, "-I", str(RUNTIME), "-I", str(tmp_path), "-c", str(src),
                              "-o", str(tmp_path / f"{name}_{kind}.o")], capture_output=True, text=True)
        assert res.returncode == 0, res.stderr
