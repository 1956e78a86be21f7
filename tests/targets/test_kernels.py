"""The fast MLP kernel on the simulated chips: bit-exact with the integer model, and fast.

galvo_cba2012 (2-6-2) and corexy_nonlinear (2-12-2 residual) are quantised with
kernel="fast", rendered to C and run on the ATmega328P (avr-gcc -Os and -O2, simavr) and the
PIC18F452 (SDCC pic16, gpsim) on corners, edges, points just and far outside the domain,
int32 extremes and random points.  Cycle counts are deterministic simulator counts, not
timings: the galvo model must meet the mission's targets (<= 1000 AVR cycles, <= 3000 PIC18
instruction cycles per IK call).

Skips when a toolchain is missing, unless NNIK_REQUIRE_TOOLCHAINS=1 (then fails).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nnik.implementations.mlp import quantize as fx
from nnik.machine.data import Dataset
from nnik.emit.templating import write_sources
from nnik.implementations.mlp.export import render_model_c
from nnik.targets import run_on_target
from tests.targets.runner_helpers import need_toolchain
from nnik.implementations.mlp.train import TrainedModel

AVR_TARGET_CYCLES = 1000  # the mission's targets for galvo_cba2012, whole NAME_ik call
PIC18_TARGET_CYCLES = 3000


def fast_build(run_dir: Path, out_dir: Path):
    """Quantise run_dir's model for the fast kernel (same calibration as the pipeline) and
    write its C to out_dir; returns the integer model."""
    model = TrainedModel.load(run_dir / "model.pt")
    ds = Dataset.load(run_dir / "data.npz")
    im = fx.quantize(model, calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]), kernel="fast")
    write_sources(render_model_c(im, "test"), out_dir)
    return im


def vectors(im, n_random: int = 180, seed: int = 7) -> np.ndarray:
    """Corners, edge midpoints, the domain's centre, points 1 um and far outside, int32
    extremes, random points (a tenth of them outside the domain)."""
    lo, hi = im.inp.lo, im.inp.hi
    mid = (lo + hi) // 2
    span = hi - lo
    corners = [[a, b] for a in (lo[0], hi[0]) for b in (lo[1], hi[1])]
    edges = [[mid[0], lo[1]], [mid[0], hi[1]], [lo[0], mid[1]], [hi[0], mid[1]], list(mid)]
    out1 = [[lo[0] - 1, mid[1]], [hi[0] + 1, mid[1]], [mid[0], lo[1] - 1], [mid[0], hi[1] + 1],
            [lo[0] - 1, lo[1] - 1], [hi[0] + 1, hi[1] + 1]]
    far = [[lo[0] - span[0], hi[1] + span[1]], [hi[0] + 3 * span[0], lo[1] - 5 * span[1]]]
    extremes = [[-(2**31), -(2**31)], [2**31 - 1, 2**31 - 1], [-(2**31), 2**31 - 1], [2**31 - 1, -(2**31)],
                [0, 2**31 - 1], [-(2**31), 0]]
    rng = np.random.default_rng(seed)
    rnd = rng.integers(lo - span // 10, hi + span // 10 + 1, (n_random, 2))
    return np.vstack([np.array(corners + edges + out1 + far + extremes, dtype=np.int64), rnd]).astype(np.int64)


@pytest.fixture(scope="module")
def galvo_fast(galvo_run, tmp_path_factory):
    d = tmp_path_factory.mktemp("galvo_fast")
    im = fast_build(galvo_run, d)
    return im, d, vectors(im)


@pytest.fixture(scope="module")
def corexy_fast(corexy_run, tmp_path_factory):
    d = tmp_path_factory.mktemp("corexy_fast")
    im = fast_build(corexy_run, d)
    return im, d, vectors(im)


def run_and_compare(im, d: Path, vec: np.ndarray, target: str, opt: str, workdir: Path) -> dict:
    res = run_on_target(target=target, sources=[d / f"{im.name}.c"], include_dirs=[d], name=im.name,
                        vectors=vec, opt=opt, workdir=workdir, progress=False)
    _, want, flags = im.run(vec)
    bad = np.any(res["outputs"] != want, axis=1) | (res["flags"] != flags)
    assert not bad.any(), (f"{target} {opt}: {int(bad.sum())} of {len(vec)} differ from the integer model, "
                           f"first at {vec[np.argmax(bad)].tolist()}: {res['outputs'][np.argmax(bad)].tolist()} "
                           f"vs {want[np.argmax(bad)].tolist()}")
    assert flags.sum() > 0 and (flags == 0).sum() > 0  # both the clamped and the in-domain path ran
    return res


def _report(capsys, what: str, res: dict) -> None:
    with capsys.disabled():
        print(f"\n[{res['target']}] {what}: {res['cycles_mean']:.0f} cycles mean, max {res['cycles_max']}; "
              f"model flash {res['model_flash_bytes']} B, RAM {res['model_ram_bytes']} B")


@pytest.mark.parametrize("opt", ["-Os", "-O2"])
def test_galvo_fast_avr_bit_exact_and_under_1000_cycles(galvo_fast, tmp_path, capsys, opt):
    need_toolchain("avr")
    im, d, vec = galvo_fast
    assert len(vec) >= 200
    res = run_and_compare(im, d, vec, "avr", opt, tmp_path)
    _report(capsys, f"galvo_cba2012 fast kernel, avr-gcc {opt}", res)
    assert res["cycles_max"] <= AVR_TARGET_CYCLES


def test_galvo_fast_pic18_bit_exact_and_under_3000_cycles(galvo_fast, tmp_path, capsys):
    need_toolchain("pic18")
    im, d, vec = galvo_fast
    res = run_and_compare(im, d, vec, "pic18", "", tmp_path)
    _report(capsys, "galvo_cba2012 fast kernel, SDCC pic16", res)
    assert res["cycles_max"] <= PIC18_TARGET_CYCLES


@pytest.mark.parametrize("target,opt", [("avr", "-Os"), ("pic18", "")])
def test_corexy_fast_bit_exact(corexy_fast, tmp_path, capsys, target, opt):
    need_toolchain(target)
    im, d, vec = corexy_fast
    assert im.out.residual and len(vec) >= 200
    res = run_and_compare(im, d, vec, target, opt or "-Os", tmp_path)
    _report(capsys, f"corexy_nonlinear fast kernel {opt}".rstrip(), res)


def test_galvo_fast_portable_c_on_avr_is_bit_exact(galvo_fast, tmp_path):
    """-DNNIK_PORTABLE: the C99 value primitives (what XC8 or CCS compile) give the same bits."""
    need_toolchain("avr")
    im, d, vec = galvo_fast
    res = run_on_target(target="avr", sources=[d / f"{im.name}.c"], include_dirs=[d], name=im.name,
                        vectors=vec[:60], opt="-Os", workdir=tmp_path, extra_cflags=["-DNNIK_PORTABLE"],
                        progress=False)
    _, want, flags = im.run(vec[:60])
    np.testing.assert_array_equal(res["outputs"], want)
    np.testing.assert_array_equal(res["flags"], flags)
