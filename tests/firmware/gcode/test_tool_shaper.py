"""The tool's step of the shaper (nnik_sh_step's tool_step, modelled in bulk by
nnik.firmware.gcode.tool_shaper): the bulk model equals the chip's loop, transliterated here sample
by sample with a ring of nnik_shaper.h's size."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.dynamics.shapers import KINDS
from nnik.firmware.config import MachineConfig, shaper_taps
from nnik.firmware.gcode.tool_shaper import shaped_duty


def chip_loop(pd, moved, cfg):
    """nnik_sh_step's third channel and tool_step as written in C, one sample at a time: the
    path length moved (Q16 um) in whole units of 2^(psh - 16) um (uint8), int32 sums, uint16 lag."""
    L, psh = cfg.shaper_len, cfg.progress_shift
    amps, delays = cfg.shaper_taps[0]
    pq, pd_r, w = [0] * L, [0] * L, [0] * len(amps)
    e = k = at = fr = 0
    ms = L - 1
    out = []
    for mv, t in zip(moved, pd):
        fr += mv
        dq, fr = fr >> psh, fr & ((1 << psh) - 1)
        assert 0 <= dq <= 255  # uint8
        s = 0
        for i, (A, dk) in enumerate(zip(amps, delays)):
            if dk:
                w[i] += dq - pq[(at - dk) % L]
                assert 0 <= w[i] < 1 << 16
                s += A * w[i]
        assert 0 <= s < 1 << 31  # int32
        lag = (s + 16383) >> 15
        assert lag < 1 << 16 and lag == -((16384 - s) >> 15)  # uint16
        pq[at], pd_r[at] = dq, t
        k, e = k + 1, e + dq
        while k > L - 1 or e > lag:
            k -= 1
            ms = 0 if ms + 1 == L else ms + 1
            e -= pq[ms]
        assert 0 <= e < 1 << 16
        out.append(pd_r[ms])
        at = 0 if at + 1 == L else at + 1
    return np.array(out, dtype=np.int64)


def move_max(cfg) -> int:
    """The most a sample of cfg's planner moves along the path, Q16 um (MachineConfig.progress_shift)."""
    return max(cfg.vn_max_q16, *cfg.acc_q16, 1)


def random_stream(seed: int, vmax: int, top: int):
    """(path length per sample (N,), Q16 um, at most top, planned points (N, 2), planned duties
    (N,)): runs of steps in one direction (rests, moves, reversals) and runs of random duties."""
    rng = np.random.default_rng(seed)
    runs = int(rng.integers(1, 12))
    steps = np.repeat(rng.integers(-vmax, vmax + 1, (runs, 2)), rng.integers(1, 60, runs), axis=0)
    steps[rng.random(len(steps)) < 0.1] = 0
    planned = np.cumsum(steps, axis=0)
    moved = np.minimum(np.hypot(*steps.T.astype(float)) * 65536 + rng.integers(0, 65536, len(steps)), top).astype(np.int64)
    moved[rng.random(len(steps)) < 0.05] = top  # the fastest
    moved[(steps == 0).all(1)] = 0
    return moved, planned, np.resize(np.repeat(rng.integers(0, 256, runs), rng.integers(1, 60, runs)), len(planned))


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(KINDS), f=st.floats(25, 90), zeta=st.floats(0.0, 0.2), hz=st.sampled_from([500, 1000]),
       seed=st.integers(0, 2**31), vmax=st.integers(1, 150), feed=st.integers(60_000, 7_000_000))
def test_bulk_model_equals_the_chips_loop(kind, f, zeta, hz, seed, vmax, feed):
    try:
        cfg = replace(MachineConfig(origin_um=(0, 0), sample_hz=hz, max_feed_um_min=feed), shaper=kind, shaper_taps=shaper_taps(kind, {"f_hz": (f, f * 0.9), "zeta": (zeta, zeta)}, hz))
    except ValueError:  # beyond the SRAM budget: refused with one line (test_shaper)
        return
    moved, _, pd = random_stream(seed, vmax, move_max(cfg))
    want = chip_loop(pd.tolist(), moved.tolist(), cfg)
    assert np.array_equal(shaped_duty(pd, moved, cfg.shaper_taps[0], cfg.shaper_len, cfg.progress_shift), want)


DRIVER = r"""
#include <stdio.h>
#include "nnik_shaper.h"
int main(void) {
    nnik_shaper_t sh; int32_t p[2], o[2] = {0, 0}, z[2] = {0, 0}; int t; long m;
    nnik_sh_init(&sh, z);
    while (scanf("%d %d %d %ld", &p[0], &p[1], &t, &m) == 4) {
        nnik_sh_step(&sh, p, (uint8_t)t, (uint32_t)m, o);
        printf("%d %d %d\n", (int)o[0], (int)o[1], sh.duty);
    }
    return 0;
}
"""


@settings(max_examples=25, deadline=None)
@given(kind=st.sampled_from(KINDS), kind_y=st.sampled_from(KINDS), f=st.floats(25, 90), zeta=st.floats(0.0, 0.2),
       hz=st.sampled_from([500, 1000]), seed=st.integers(0, 2**31), vmax=st.integers(1, 150),
       feed=st.integers(60_000, 7_000_000))
def test_the_c_shaper_equals_the_model(tmp_path_factory, kind, kind_y, f, zeta, hz, seed, vmax, feed):
    """nnik_shaper.c itself, built for the host with gcc: the shaped points and the tool's duty
    of every sample equal planner.Shaper's and tool_shaper's (different shapers per axis too)."""
    import subprocess
    from pathlib import Path

    from nnik.firmware.gcode.planner import Shaper
    from tests.conftest import require_tool

    require_tool("gcc")
    dyn = {"f_hz": (f, f * 0.8), "zeta": (zeta, zeta)}
    tx, ty = shaper_taps(kind, dyn, hz), shaper_taps(kind_y, dyn, hz)
    try:
        cfg = replace(MachineConfig(origin_um=(0, 0), sample_hz=hz, max_feed_um_min=feed), shaper=f"{kind}/{kind_y}",
                      shaper_taps=(tx[0], ty[1]))
    except ValueError:  # beyond the SRAM budget: refused with one line (test_shaper)
        return
    src = Path(__file__).resolve().parents[3] / "codegen"
    work = tmp_path_factory.mktemp("shaper_c")
    (work / "nnik_gcode_config.h").write_text("".join(f"#define {k} {v}\n" for k, v in cfg.motion_defines().items()
                                                      if k.startswith("NNIK_SH")))
    (work / "drv.c").write_text(DRIVER)
    subprocess.run(["gcc", "-std=c99", "-O1", "-Wall", "-Werror", f"-I{work}", f"-I{src / 'arduino' / 'src'}",
                    f"-I{src / 'runtime'}", str(work / "drv.c"), str(src / "arduino" / "src" / "nnik_shaper.c"),
                    "-o", str(work / "drv")], check=True)
    moved, planned, pd = random_stream(seed, vmax, move_max(cfg))
    text = "".join(f"{x} {y} {t} {m}\n" for (x, y), t, m in zip(planned.tolist(), pd.tolist(), moved.tolist()))
    got = np.array([[int(v) for v in ln.split()] for ln in subprocess.run(
        [str(work / "drv")], input=text, capture_output=True, text=True, check=True).stdout.splitlines()])
    sh = Shaper(cfg)
    assert np.array_equal(got[:, :2], np.array([sh.step(tuple(p)) for p in planned.tolist()]))
    assert np.array_equal(got[:, 2], shaped_duty(pd, moved, cfg.shaper_taps[0], cfg.shaper_len, cfg.progress_shift))
