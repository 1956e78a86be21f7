"""nnik_imath.c's AVR assembly paths (nnik_div64_32, nnik_isqrt32, nnik_isqrt_hl's loop) and the
narrower paths of nnik_div_round and nnik_mul_r on the ATmega328P
(avr-gcc + simavr) against Python's exact integers, at random (hypothesis) and at the edges: the
same values as the portable C (tests/firmware/gcode/test_imath.py checks that on the host)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.targets.toolchain import HARNESS_DIR, find_tool

SRC = HARNESS_DIR.parent / "arduino" / "src"
WRAP = """#include "nnik_imath.h"
int8_t imath_ik(const int32_t in[4], int32_t out[2])
{
    uint32_t a = (uint32_t)in[1], b = (uint32_t)in[2], c = (uint32_t)in[3];
    int64_t p;
    out[1] = 0;
    if (in[0] == 4) { /* nnik_mul_r: the product's two words */
        p = nnik_mul_r(in[1], b);
        out[0] = (int32_t)(uint32_t)p;
        out[1] = (int32_t)(uint32_t)((uint64_t)p >> 32);
    } else if (in[0] == 3)
        out[0] = nnik_div_round((int64_t)(((uint64_t)a << 32) | b), c);
    else
        out[0] = (int32_t)(in[0] == 2 ? nnik_isqrt32(b) : in[0] ? nnik_div64_32(a, b, c) : nnik_isqrt_hl(a, b));
    return 0;
}
"""
U32 = st.integers(0, (1 << 32) - 1)


def s32(v: int) -> int:
    return v - (1 << 32) if v >= 1 << 31 else v


@pytest.fixture(scope="module")
def avr(tmp_path_factory):
    if find_tool("avr-gcc") is None or find_tool("simavr") is None:
        pytest.skip("no avr-gcc/simavr")
    from nnik.targets.avr import run_avr
    wd = tmp_path_factory.mktemp("imath_avr")
    (wd / "wrap.c").write_text(WRAP)

    def ask(rows: list[tuple[int, int, int, int]]) -> list[int]:
        vec = np.asarray([[op, s32(a), s32(b), s32(c)] for op, a, b, c in rows], dtype=np.int64)
        r = run_avr([wd / "wrap.c", SRC / "nnik_imath.c"], [SRC], "imath", vec, workdir=wd, progress=False)
        return [int(v) & 0xFFFFFFFF | (int(w) & 0xFFFFFFFF) << 32 if op == 4 else int(v) & 0xFFFFFFFF
                for op, (v, w) in zip(vec[:, 0], r["outputs"][:, :2])]
    return ask


def isqrt_rows(vs):
    return [(0, v >> 32, v & 0xFFFFFFFF, 0) for v in vs]


def isqrt32_rows(vs):
    return [(2, 0, v, 0) for v in vs]


def div_rows(rows):
    return [(1, hi % d, lo, d) for d, lo, hi in rows]  # hi < d: the quotient fits 32 bits


def div_round_rows(rows):
    return [(3, (a >> 32) & 0xFFFFFFFF, a & 0xFFFFFFFF, b) for a, b in rows]


def div_round_want(rows):
    """round(a / b) half away from zero, as a uint32 word (the results fit int32)"""
    return [(-1 if a < 0 else 1) * ((2 * abs(a) + b) // (2 * b)) & 0xFFFFFFFF for a, b in rows]


def mul_r_rows(rows):
    return [(4, x & 0xFFFFFFFF, r, 0) for x, r in rows]


EDGE_SQ = [0, 1, 2, 3, (1 << 32) - 1, 1 << 32, (1 << 32) + 1, (1 << 60) - 1, 1 << 60, (1 << 62) - 1, 1 << 62,
           (1 << 64) - 1, *(k * k + e for k in (1 << 16, 1 << 31, 3037000499, (1 << 32) - 1) for e in (-1, 0, 1))]
EDGE_DIV = [(1, 0, 0), (1, 0xFFFFFFFF, 0), ((1 << 32) - 1, 0xFFFFFFFF, (1 << 32) - 2), (1 << 31, 0, (1 << 31) - 1),
            ((1 << 31) + 1, 0xFFFFFFFF, 1 << 31), (3, 5, 2), ((1 << 32) - 1, 0, 0)]


# a / b that fit int32 (both division paths: |a| and b below and above 2^30), and products at the ends
EDGE_DR = [(0, 1), (65535, 1), (65535 * 2 + 1, 2), (-(1 << 17), 3), ((1 << 29) - 1, 1 << 13), ((1 << 30) - 1, 1), (1, 2), (-1, 2), (3, 2), (-3, 2), ((1 << 31) - 1, 1), (-(1 << 31) + 1, 1), ((1 << 40) + 7, 1 << 12),
           (-(1 << 61), (1 << 31) - 1), ((1 << 62) - 1, (1 << 32) - 1), ((1 << 30) - 1, (1 << 30) - 1),
           (1 << 30, 1 << 30), (-(1 << 30), (1 << 31) + 1), ((1 << 32) * 3 + 5, (1 << 31)), ((1 << 31) * 5 + (1 << 30), 1 << 31)]
EDGE_MR = [(0, 0), (-1, (1 << 32) - 1), (-(1 << 31), (1 << 32) - 1), ((1 << 31) - 1, (1 << 32) - 1), (65535, 65535),
           (-65535, 65535), (65536, 1), (-65536, 65536)]


def test_div_round_and_mul_r_on_the_chip(avr):
    assert avr(div_round_rows(EDGE_DR)) == div_round_want(EDGE_DR)
    assert avr(mul_r_rows(EDGE_MR)) == [x * r & (1 << 64) - 1 for x, r in EDGE_MR]


@settings(max_examples=8, deadline=None)
@given(st.lists((st.tuples(st.integers(-(1 << 62), 1 << 62), st.integers(1, (1 << 32) - 1))
                 | st.tuples(st.integers(-(1 << 30) + 1, (1 << 30) - 1), st.integers(1, (1 << 30) - 1))
                 | st.tuples(st.integers(-(1 << 24), 1 << 24), st.integers(1, 1 << 12)))
                .filter(lambda ab: abs(ab[0]) // ab[1] < (1 << 31) - 1), min_size=1, max_size=300),
       st.lists(st.tuples(st.integers(-(1 << 31), (1 << 31) - 1), U32), min_size=1, max_size=300))
def test_div_round_and_mul_r_random_on_the_chip(avr, drs, mrs):
    assert avr(div_round_rows(drs)) == div_round_want(drs)
    assert avr(mul_r_rows(mrs)) == [x * r & (1 << 64) - 1 for x, r in mrs]


def test_edges_on_the_chip(avr):
    e32 = [v for v in EDGE_SQ if v < 1 << 32] + [(1 << k) + e for k in range(32) for e in (-1, 0, 1)]
    rows = isqrt_rows(EDGE_SQ) + isqrt32_rows(e32) + div_rows(EDGE_DIV)
    want = [math.isqrt(v) for v in EDGE_SQ] + [math.isqrt(v) for v in e32] + [((hi << 32) | lo) // d for _, hi, lo, d in div_rows(EDGE_DIV)]
    assert avr(rows) == want


@settings(max_examples=8, deadline=None)
@given(st.lists(st.integers(0, (1 << 64) - 1) | st.integers(0, (1 << 62) - 1).map(lambda k: k | 1 << 60),
                min_size=1, max_size=300),
       st.lists(U32 | st.integers(0, 1 << 20), min_size=1, max_size=300),
       st.lists(st.tuples(st.integers(1, (1 << 32) - 1), U32, U32), min_size=1, max_size=300))
def test_random_on_the_chip(avr, vs, v32, divs):
    rows = isqrt_rows(vs) + isqrt32_rows(v32) + div_rows(divs)
    want = [math.isqrt(v) for v in vs] + [math.isqrt(v) for v in v32] + [((hi << 32) | lo) // d for _, hi, lo, d in div_rows(divs)]
    assert avr(rows) == want
