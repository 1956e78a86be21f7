"""nnik_sh_step on the ATmega328P (avr-gcc -Os, simavr): its multiply-accumulates in AVR assembly
(nnik_shaper.h) give the shaped points and the tool's duty of planner.Shaper and tool_shaper,
sample for sample, on random streams (runs, rests, reversals, the fastest moves) and shapers."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.dynamics.shapers import KINDS
from nnik.firmware.config import MachineConfig, shaper_taps
from nnik.firmware.gcode.planner import Shaper
from nnik.firmware.gcode.tool_shaper import shaped_duty
from tests.conftest import require_tool
from tests.firmware.gcode.test_tool_shaper import move_max, random_stream

SRC = Path(__file__).resolve().parents[3] / "codegen"
# one call a row: (x, y, planned duty, path length moved); the first row starts the shaper at (x, y)
WRAP = r"""#include "nnik_shaper.h"
static nnik_shaper_t sh;
int8_t shavr_ik(const int32_t in[4], int32_t out[2])
{
    if (in[3] < 0) {
        nnik_sh_init(&sh, in);
        out[0] = out[1] = 0;
        return 0;
    }
    nnik_sh_step(&sh, in, (uint8_t)in[2], (uint32_t)in[3], out);
    return (int8_t)sh.duty;
}
"""


@settings(max_examples=25, deadline=None, database=None)
@given(kind=st.sampled_from(KINDS), kind_y=st.sampled_from(KINDS), f=st.floats(25, 90), zeta=st.floats(0.0, 0.2),
       hz=st.sampled_from([500, 1000]), seed=st.integers(0, 2**31), vmax=st.integers(1, 150),
       feed=st.integers(60_000, 7_000_000))
def test_the_avr_shaper_equals_the_model(tmp_path_factory, kind, kind_y, f, zeta, hz, seed, vmax, feed):
    from nnik.targets.avr import run_avr

    for tool in ("avr-gcc", "simavr"):
        require_tool(tool)
    dyn = {"f_hz": (f, f * 0.8), "zeta": (zeta, zeta)}
    same = kind == kind_y and seed % 2  # both axes on one set of taps (NNIK_SH_SAME) half the time
    tx, ty = shaper_taps(kind, dyn, hz), shaper_taps(kind_y, dyn, hz)
    taps = (tx[0], tx[0]) if same else (tx[0], ty[1])
    try:
        cfg = replace(MachineConfig(origin_um=(0, 0), sample_hz=hz, max_feed_um_min=feed), shaper=f"{kind}/{kind_y}",
                      shaper_taps=taps)
    except ValueError:  # beyond the SRAM budget: refused with one line (test_shaper)
        return
    work = tmp_path_factory.mktemp("shaper_avr")
    (work / "nnik_gcode_config.h").write_text("".join(f"#define {k} {v}\n" for k, v in cfg.motion_defines().items()
                                                      if k.startswith("NNIK_SH")))
    (work / "w.c").write_text(WRAP)
    moved, planned, pd = random_stream(seed, vmax, move_max(cfg))
    planned = planned[:900]
    moved, pd = moved[:len(planned)], pd[:len(planned)]
    rows = np.concatenate([[[0, 0, 0, -1]], np.column_stack([planned, pd, moved])]).astype(np.int64)
    r = run_avr([work / "w.c", SRC / "arduino" / "src" / "nnik_shaper.c"], [work, SRC / "arduino" / "src",
                SRC / "runtime"], "shavr", rows, workdir=work, n_out=2, progress=False, batch_size=len(rows),
                extra_cflags=["-mcall-prologues"])
    got = np.asarray(r["outputs"])[1:]
    sh = Shaper(cfg)
    assert np.array_equal(got, np.array([sh.step(tuple(p)) for p in planned.tolist()]))
    duty = np.asarray(r["flags"])[1:].astype(np.int64) & 0xFF
    assert np.array_equal(duty, shaped_duty(pd, moved, cfg.shaper_taps[0], cfg.shaper_len, cfg.progress_shift))
