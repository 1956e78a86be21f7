"""The bulk sampler (nnik/firmware/gcode/sampler.py, run_ops) against the
sample-by-sample definition (planner.run_ops_reference: Planner.sample and Shaper.step): the same
stream, field for field, on random jobs with lines, arcs, dwells, tool changes and M400, with and
without a shaper."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.firmware.config import MachineConfig, shaper_taps
from nnik.firmware.gcode.motion import interpret
from nnik.firmware.gcode.planner import run_ops_reference
from nnik.firmware.gcode.sampler import run_ops

BASE = MachineConfig(origin_um=(0, 0))
TAPS = {"f_hz": (40.0, 25.0), "zeta": (0.1, 0.05)}
FIELDS = ("kind", "planned", "shaped", "speed", "vn", "tool", "rest_ticks", "block")


def cfg_for(shaper: str, sample_hz: int) -> MachineConfig:
    cfg = replace(BASE, sample_hz=sample_hz)
    if shaper == "none":
        return cfg
    return replace(cfg, shaper=shaper, shaper_taps=shaper_taps(shaper, TAPS, sample_hz))


line = st.tuples(st.integers(-30000, 30000), st.integers(-30000, 30000), st.integers(300, 9000))
word = st.one_of(line.map(lambda t: f"G1 X{t[0] / 1000:.3f} Y{t[1] / 1000:.3f} F{t[2]}"),
                 line.map(lambda t: f"G0 X{t[0] / 1000:.3f} Y{t[1] / 1000:.3f}"),
                 st.sampled_from(["G4 P0.05", "M400", "M3 S500", "M4 S300", "M5", "G2 I2 J0", "G3 I0 J-1.5",
                                  "G91 G1 X0.01", "G90"]))


@settings(max_examples=60, deadline=None, database=None)
@given(lines=st.lists(word, min_size=1, max_size=25), shaper=st.sampled_from(["none", "zv", "zvd", "ei"]),
       sample_hz=st.sampled_from([1000, 500]), search=st.booleans())
def test_the_bulk_sampler_is_the_sample_by_sample_one(lines, shaper, sample_hz, search):
    """Both sampler rules (MachineConfig.speed_search: the chip's search, the closed-loop
    reference's hold-else-down)."""
    cfg = replace(cfg_for(shaper, sample_hz), speed_search=search)
    plan = interpret(["G21", "G90", *lines, "G1 X40 F6000", "G1 X-40"], cfg)
    fast, ref = run_ops(plan.ops, cfg), run_ops_reference(plan.ops, cfg)
    for f in FIELDS:
        assert getattr(fast, f) == [tuple(x) if isinstance(x, tuple) else x for x in getattr(ref, f)], f


def test_the_search_is_the_chips_and_the_closed_loop_reference_keeps_hold_else_down():
    """A build from a configuration without the search is refused (the chip always searches); the
    closed-loop reference's configuration has it off, and on a stop the two rules differ."""
    import pytest

    from nnik.job.reference import servo_machine
    from nnik.machine.scenario import load_scenario

    with pytest.raises(ValueError, match="always searches"):
        replace(BASE, speed_search=False).defines()
    assert not servo_machine(load_scenario(Path(__file__).resolve().parents[3] / "datasets" / "xy_table.toml"), None).speed_search
    plan = interpret(["G1 X100 F3000"], BASE)
    on, off = run_ops(plan.ops, BASE).speed, run_ops(plan.ops, replace(BASE, speed_search=False)).speed
    assert on != off and len(on) == len(off)
