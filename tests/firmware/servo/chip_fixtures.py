"""Shared by the servo chip's tests: one firmware build per controller kind (seeded gains, 5 ms
tick) and random references (holds, ramps, and steps big enough to saturate the duty: fast moves)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from nnik.firmware.servo.build import build_firmware
from nnik.implementations.servo import make
from tests.conftest import require_tool
from tests.implementations.servo.sequences import seeded_gains

TICK_S = 0.005
_BUILDS: dict = {}


def shipped_cfg():
    """datasets/xy_table.toml's plant."""
    from nnik.machine.scenario import load_scenario
    return load_scenario("datasets/xy_table.toml").servo


def controller(kind: str, cfg):
    return make(kind, seeded_gains(kind, 3), cfg)


def firmware(kind: str, cfg, root: Path):
    """The co-simulation firmware of `kind` (built once per kind and tick for the session)."""
    require_tool("avr-gcc")
    require_tool("simavr")
    key = (kind, cfg.tick_s)
    if key not in _BUILDS:
        _BUILDS[key] = build_firmware(controller(kind, cfg), cfg.tick_s, root / f"fw-{kind}-{cfg.tick_s:g}")
    return _BUILDS[key]


SEGMENT = st.tuples(st.integers(1, 25), st.sampled_from(["hold", "ramp", "step"]),
                    st.integers(-60, 60), st.integers(-60, 60), st.integers(-30000, 30000), st.integers(-30000, 30000))


@st.composite
def references(draw, max_ticks: int = 80) -> np.ndarray:
    """(N, 2) int64 reference counts, N <= max_ticks."""
    segs = draw(st.lists(SEGMENT, min_size=1, max_size=6))
    ref = np.array([draw(st.integers(-2000, 2000)), draw(st.integers(-2000, 2000))], dtype=np.int64)
    rows = []
    for n, what, vx, vy, sx, sy in segs:
        if what == "step":
            ref = ref + np.array([sx, sy])
        v = np.array([vx, vy]) if what == "ramp" else np.zeros(2, dtype=np.int64)
        for _ in range(n):
            ref = ref + v
            rows.append(ref.copy())
    return np.array(rows[:max_ticks], dtype=np.int64)
