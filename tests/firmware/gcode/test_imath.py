"""nnik_imath.c's square root and 64/32 division (the planner's, by 32-bit steps on AVR) against
Python's exact integers, on the host (gcc with the sanitizers), at random and at the edges."""

from __future__ import annotations

import math
import shutil
import subprocess

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.targets.host import HOST_FLAGS
from nnik.targets.toolchain import HARNESS_DIR

SRC = HARNESS_DIR.parent / "arduino" / "src"


@pytest.fixture(scope="module")
def imath(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("no host gcc")
    exe = tmp_path_factory.mktemp("imath") / "imath"
    subprocess.run(["gcc", *HOST_FLAGS, f"-I{SRC}", str(HARNESS_DIR / "arduino" / "nnik_imath_host.c"),
                    str(SRC / "nnik_imath.c"), "-o", str(exe)], check=True, capture_output=True)

    def ask(lines: list[str]) -> list[int]:
        out = subprocess.run([str(exe)], input="".join(f"{ln}\n" for ln in lines), capture_output=True, text=True,
                             check=True).stdout.split()
        return [int(x) for x in out]
    return ask


def squares_near(k: int) -> list[int]:
    return [v for v in (k * k - 1, k * k, k * k + 1) if 0 <= v < 1 << 64]


EDGES = [0, 1, 2, 3, (1 << 32) - 1, 1 << 32, (1 << 60) - 1, 1 << 60, (1 << 62) - 1, 1 << 62, (1 << 64) - 1,
         *(v for k in (1 << 16, (1 << 16) + 1, 1 << 31, 3037000499, (1 << 32) - 1) for v in squares_near(k))]


def test_isqrt64_at_the_edges(imath):
    assert imath([f"s {v}" for v in EDGES]) == [math.isqrt(v) for v in EDGES]


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(0, (1 << 64) - 1) | st.integers(0, (1 << 62) - 1).map(lambda k: k | 1 << 60), min_size=1,
                max_size=400))
def test_isqrt64_is_floor_sqrt(imath, vs):
    assert imath([f"s {v}" for v in vs]) == [math.isqrt(v) for v in vs]


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.integers(1, (1 << 32) - 1), st.integers(0, (1 << 32) - 1), st.integers(0, (1 << 32) - 1)),
                min_size=1, max_size=400))
def test_div64_32_is_floor_division(imath, rows):
    rows = [(hi % d, lo, d) for d, lo, hi in rows]  # the quotient fits 32 bits: hi < d
    assert imath([f"d {hi} {lo} {d}" for hi, lo, d in rows]) == [((hi << 32) | lo) // d for hi, lo, d in rows]
