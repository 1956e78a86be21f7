"""The input shaper of the firmware (nnik/firmware/gcode/planner.py Shaper, the model of
nnik_shaper.c): its taps from nnik.dynamics, the exact weighted sum it rounds, the motion it
leaves where it was, and its SRAM."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.dynamics.shapers import KINDS
from nnik.firmware.config import MachineConfig, shaper_taps
from nnik.firmware.gcode.motion import interpret
from nnik.firmware.gcode.planner import Shaper
from nnik.firmware.gcode.sampler import run_ops

BELT = {"f_hz": (40.0, 35.0), "zeta": (0.1, 0.05)}


def cfg_with(kind: str, dyn=BELT, **kw) -> MachineConfig:
    base = MachineConfig(origin_um=(0, 0), **kw)
    return base if kind == "none" else replace(base, shaper=kind, shaper_taps=shaper_taps(kind, dyn, base.sample_hz))


@pytest.mark.parametrize("kind", KINDS)
def test_taps_sum_to_one_in_q15_per_axis_and_differ_by_axis(kind):
    cfg = cfg_with(kind)
    (ax, dx), (ay, dy) = cfg.shaper_taps
    assert sum(ax) == sum(ay) == 32768 and min(ax + ay) > 0
    assert dx != dy  # 40 Hz and 35 Hz: other delays
    periods = {"2hump_ei": 1.55, "3hump_ei": 2.05}.get(kind, 1.05)  # the longest: 1.5 and 2 periods
    assert dx[0] == 0 and 0.45 / 40 <= max(dx) / cfg.sample_hz <= periods / 40 / (1 - 0.01) ** 0.5 + 1e-3


def test_zvd_at_40_hz_fits_the_sram_goal():
    cfg = cfg_with("zvd", {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)})
    assert cfg.shaper_len == 26 and cfg.shaper_ram_bytes <= 256  # issue 18: <= 256 B; Marlin's ZV ~900 B
    assert cfg.defines()["NNIK_SH_LEN"] == "26"


@settings(max_examples=60, deadline=None, database=None)
@given(kind=st.sampled_from(KINDS), steps=st.lists(st.integers(-100, 100), min_size=1, max_size=120),
       x0=st.integers(-10**6, 10**6))
def test_shaped_is_the_rounded_weighted_sum_of_past_samples(kind, steps, x0):
    """shaped[n] = floor((sum_i A_i p[n - d_i] + 16384) / 32768), p before the start = the start:
    computed here directly from the definition, not by the firmware's running sums."""
    cfg = cfg_with(kind)
    p = x0 + np.cumsum(steps)
    sh = Shaper(cfg, (x0, -x0))
    got = [sh.step((int(v), -int(v))) for v in p]
    for axis, sign in ((0, 1), (1, -1)):
        amps, delays = cfg.shaper_taps[axis]
        hist = np.concatenate([np.full(max(delays), sign * x0), sign * p])
        n0 = max(delays)
        want = [(sum(a * int(hist[n0 + n - d]) for a, d in zip(amps, delays)) + 16384) // 32768 for n in range(len(p))]
        assert [g[axis] for g in got] == want


@pytest.mark.parametrize("kind", ["none", *KINDS])
def test_the_shaped_motion_ends_where_the_planned_one_does(kind):
    cfg = cfg_with(kind)
    plan = interpret(["G1 X10 Y3 F3000", "G1 X0 Y8", "G2 X0 Y0 I0 J-4", "G4 P0.01", "G1 X5"], cfg)
    st_ = run_ops(plan.ops, cfg)
    kind_ = np.asarray(st_.kind)
    planned, shaped = np.asarray(st_.planned), np.asarray(st_.shaped)
    rest = np.flatnonzero(kind_ == 1)[0]
    assert tuple(shaped[rest - 1]) == tuple(planned[rest - 1]) == (0, 0)  # settled before the dwell
    assert tuple(shaped[-1]) == (5000, 0)
    if kind == "none":
        assert np.array_equal(planned, shaped)
    else:  # the shaper's tail: its longest delay in samples after each stop
        tail = np.asarray(st_.block) == -1
        assert (tail & (kind_ == 0)).sum() == 2 * cfg.shaper_len
        assert np.abs(shaped - planned).max() > 10  # it does move the corners


def test_a_shaper_too_long_for_the_budget_is_one_line():
    with pytest.raises(ValueError, match="SRAM") as exc:
        cfg_with("zvd", {"f_hz": (4.0, 40.0), "zeta": (0.1, 0.1)})
    assert "\n" not in str(exc.value)
