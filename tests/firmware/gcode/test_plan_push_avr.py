"""nnik_pl_push on the ATmega328P (avr-gcc + simavr, with its AVR-only paths: nnik_imath.c's
assembly, the word-wise shifts and dot product) equals planner.py's push, block field for block
field and exit for exit, on random paths (hypothesis): chords of 1 um to 0.5 mm, long lines,
corners and reversals, feed changes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.bench.plan_push import SRC, header
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.planner import Planner
from nnik.targets.toolchain import find_tool

N = 8
WRAP = """#include "nnik_plan.h"
static nnik_plan_t pl;
int8_t plchk_ik(const int32_t in[4], int32_t out[%d])
{
    uint8_t k;
    const nnik_pl_block_t *b;
    if (in[0] == 0) {
        int32_t p[2] = {in[1], in[2]};
        nnik_pl_init(&pl, p);
        for (k = 0; k < %d; k++)
            out[k] = 0;
        return 0;
    }
    nnik_pl_push(&pl, in[1], in[2], in[3], 0);
    b = &pl.q[(uint8_t)(pl.head + pl.count - 1) %% NNIK_PL_N];
    out[0] = (int32_t)b->len;
    out[1] = b->lfr;
    out[2] = b->u[0];
    out[3] = b->u[1];
    out[4] = (int32_t)b->acc;
    out[5] = (int32_t)b->vn;
    out[6] = pl.count;
    for (k = 0; k < NNIK_PL_N; k++) /* jmax and exit of every block queued, the head first */
        if (k < pl.count) {
            out[7 + 2 * k] = (int32_t)pl.q[(uint8_t)(pl.head + k) %% NNIK_PL_N].jmax;
            out[8 + 2 * k] = (int32_t)pl.q[(uint8_t)(pl.head + k) %% NNIK_PL_N].exit;
        } else
            out[7 + 2 * k] = out[8 + 2 * k] = 0;
    return 0;
}
"""
N_OUT = 7 + 2 * N


def s32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v >= 1 << 31 else v


@pytest.fixture(scope="module")
def chip(tmp_path_factory):
    if find_tool("avr-gcc") is None or find_tool("simavr") is None:
        pytest.skip("no avr-gcc/simavr")
    from nnik.targets.avr import run_avr
    cfg = MachineConfig(origin_um=(0, 0), plan_blocks=N)
    wd = tmp_path_factory.mktemp("plan_push_avr")
    (wd / "nnik_gcode_config.h").write_text(header(cfg))
    (wd / "plchk.c").write_text(WRAP % (N_OUT, N_OUT))

    def run(paths):
        rows = []
        for pts in paths:
            rows.append([0, 0, 0, 0])
            rows += [[1, x, y, f] for x, y, f in pts]
        r = run_avr([wd / "plchk.c", SRC / "nnik_plan.c", SRC / "nnik_imath.c"], [wd, SRC], "plchk",
                    np.asarray(rows, dtype=np.int64), workdir=wd, n_out=N_OUT, progress=False, batch_size=4000)
        return cfg, [list(map(int, o)) for o, row in zip(r["outputs"], rows) if row[0] == 1]
    return run


def model(cfg, paths):
    out = []
    for pts in paths:
        pl = Planner(cfg, (0, 0))
        for x, y, f in pts:
            pl.push(x, y, f, 0, 0)
            b = pl.q[-1]
            row = [b.len, b.lfr, b.u[0], b.u[1], b.acc, b.vn, len(pl.q)]
            for k in range(N):
                row += [pl.q[k].jmax, pl.q[k].exit] if k < len(pl.q) else [0, 0]
            out.append([s32(v) for v in row])
    return out


STEP = st.tuples(st.sampled_from([1, 7, 100, 500, 3000, 250_000]), st.floats(0, 6.283), st.sampled_from([0, 1, 2]),
                 st.sampled_from([60_000, 600_000, 1_800_000, 6_000_000]))


def path(steps):
    """N - 1 distinct moves from the origin (the queue never full: no sample needed)"""
    pts, x, y = [], 0, 0
    for d, ang, kind, feed in steps:
        if kind == 1 and pts:  # a reversal of the last move
            px, py = pts[-2][:2] if len(pts) > 1 else (0, 0)
            nx, ny = px, py
        else:
            nx, ny = x + round(d * np.cos(ang)), y + round(d * np.sin(ang))
        if (nx, ny) != (x, y):
            pts.append((nx, ny, feed))
            x, y = nx, ny
    return pts


@settings(max_examples=6, deadline=None)
@given(st.lists(st.lists(STEP, min_size=1, max_size=N - 1), min_size=1, max_size=60))
def test_push_on_the_chip_equals_the_model(chip, walks):
    paths = [p for p in (path(w) for w in walks) if p]
    if not paths:
        return
    cfg, got = chip(paths)
    assert got == model(cfg, paths)


# nnik_plan_sample.c's mul_q30 (static: the wrapper includes the file) on the chip, with its AVR path
# (the byte products in assembly), against floor(u s / 2^30), as the model's position
Q30_WRAP = """#include "nnik_plan_sample.c"
int8_t q30chk_ik(const int32_t in[2], int32_t out[1])
{
    out[0] = mul_q30(in[0], (uint32_t)in[1]);
    return 0;
}
"""
Q30_EDGES = [(u, s) for u in (0, 1, -1, 1 << 30, -(1 << 30), (1 << 30) - 1, -(1 << 30) + 1, 12345, -12345)
             for s in (0, 1, (1 << 29) - 1, 1 << 28, 0xFFFF, 0x10000, 77)]


@pytest.fixture(scope="module")
def q30_chip(tmp_path_factory):
    if find_tool("avr-gcc") is None or find_tool("simavr") is None:
        pytest.skip("no avr-gcc/simavr")
    from nnik.targets.avr import run_avr
    wd = tmp_path_factory.mktemp("mul_q30_avr")
    (wd / "nnik_gcode_config.h").write_text(header(MachineConfig(origin_um=(0, 0), plan_blocks=N)))
    (wd / "q30chk.c").write_text(Q30_WRAP)

    def run(pairs):
        r = run_avr([wd / "q30chk.c", SRC / "nnik_imath.c"], [wd, SRC], "q30chk", np.asarray(pairs, dtype=np.int64),
                    workdir=wd, n_out=1, progress=False, batch_size=4000)
        return [int(o[0]) for o in r["outputs"]]
    return run


@settings(max_examples=4, deadline=None)
@given(st.lists(st.tuples(st.integers(-(1 << 30), 1 << 30), st.integers(0, (1 << 29) - 1)), min_size=1, max_size=300))
def test_mul_q30_on_the_chip_is_the_floor_of_the_product(q30_chip, pairs):
    pairs = Q30_EDGES + pairs
    assert q30_chip(pairs) == [(u * s) >> 30 for u, s in pairs]
