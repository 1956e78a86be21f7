"""The planner's lookahead per chip (issue 26 item 2): the Mega runs grbl's 16 blocks, chip = model;
the Uno runs the deepest queue that leaves the stack its room (256 B at least; the sketch's stack
measured 510 B deep, ranges.STACK_RESERVE_BYTES), by the RAM formula
(nnik.machine.ranges.plan_blocks_for), which the real build's avr-size figures must not exceed."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

from nnik.firmware.arduino import export_arduino
from nnik.firmware.config import shaper_taps
from nnik.firmware.gcode import chip
from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.firmware.gcode.job_input import read_job
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.gcode.steps import chip_events, model_events
from nnik.machine import ranges

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"
ZVD = {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)}


@given(st.integers(0, ranges.SHAPER_RAM_BUDGET))
def test_the_uno_depth_is_the_deepest_that_leaves_the_stack_its_room(shaper_ram):
    n = ranges.plan_blocks_for("atmega328p", shaper_ram)
    left = lambda k: ranges.MCU_RAM_BYTES["atmega328p"] - ranges.gcode_ram_bytes(k, shaper_ram)  # noqa: E731
    assert 2 <= n <= ranges.PLAN_BLOCKS_MAX
    if left(2) < ranges.STACK_RESERVE_BYTES:  # a shaper too long for the Uno: the planner's least queue
        assert n == 2
        return
    assert left(n) >= ranges.STACK_RESERVE_BYTES
    assert n == ranges.PLAN_BLOCKS_MAX or left(n + 1) < ranges.STACK_RESERVE_BYTES
    assert ranges.plan_blocks_for("atmega2560", shaper_ram) == 16


def sender_build(run, cfg, work: Path):
    lib = export_arduino(run, work / "lib", cfg)
    return chip.build_sketch(work / "lib", f"{lib['name']}_gcode", work / "build", cfg.defines(), mcu=cfg.mcu)


@pytest.mark.parametrize("shaper", ["none", "zvd"])
def test_the_uno_build_at_its_depth_leaves_the_stack_its_room_by_avr_size(firmware, shaper, tmp_path):
    """The sender build (nnik export --arduino) at the chosen depth: the formula never under-counts
    the measured static RAM, the stack keeps >= 256 B, and the circle job's deepest stack (on simavr)
    is within the reserve, so it never reaches the static RAM."""
    run, lib, _, _, _ = firmware["galvo_cba2012"]
    cfg = replace(lib["machine"], plan_blocks=0)
    if shaper != "none":
        cfg = replace(cfg, shaper=shaper, shaper_taps=shaper_taps(shaper, ZVD, cfg.sample_hz))
    fw = sender_build(run, cfg, tmp_path)
    assert cfg.defines()["NNIK_PL_N"] == str(cfg.lookahead)
    assert ranges.gcode_ram_bytes(cfg.lookahead, cfg.shaper_ram_bytes) >= fw.ram_bytes
    assert chip.RAM_BYTES - fw.ram_bytes >= ranges.STACK_RESERVE_BYTES >= 256
    res = chip.run_firmware(fw, [ln.decode("latin-1") for ln in read_job(JOBS / "circle.gcode")], tmp_path / "build", 60.0)
    assert res.state == "done" and all(t == "ok" for _, t in res.replies[1:]) and 0 < res.stack_bytes <= ranges.STACK_RESERVE_BYTES


def short_chords(r_mm: float = 3.0, chord_mm: float = 0.05, f: int = 3000) -> list[str]:
    """Half a circle in 0.05 mm G1 chords, where the queue's depth sets the speed."""
    n = int(math.pi * r_mm / chord_mm)
    return ["G21 G90", f"G1 X{r_mm:.3f} Y0 F{f}"] + [
        f"G1 X{r_mm * math.cos(math.pi * k / n):.3f} Y{r_mm * math.sin(math.pi * k / n):.3f}" for k in range(1, n + 1)]


@pytest.mark.parametrize("job", ["circle", "short chords"])
def test_the_mega_runs_16_blocks_step_for_step_with_the_model(firmware, job, tmp_path):
    """The Mega's build at its default depth (16) against the model on the same cfg: the shipped
    circle, and short chords, where 8 blocks would give another motion (so a depth mismatch shows)."""
    run, lib, _, ik, _ = firmware["galvo_cba2012"]
    cfg = replace(lib["machine"], mcu="atmega2560", plan_blocks=0)
    assert cfg.lookahead == 16
    lib = export_arduino(run, tmp_path / "lib", cfg)
    fw = chip.build_sketch(tmp_path / "lib", f"{lib['name']}_gcode", tmp_path / "build", chip.file_run_defines(cfg),
                           mcu="atmega2560")
    lines = short_chords() if job == "short chords" else [ln.decode("latin-1") for ln in read_job(JOBS / f"{job}.gcode")]
    seg = plan_steps(interpret(lines, cfg), cfg, ik)
    if job == "short chords":
        shallow = replace(cfg, plan_blocks=8)
        assert plan_steps(interpret(lines, shallow), shallow, ik).ticks.sum() > seg.ticks.sum()
    res = chip.run_firmware(fw, lines, tmp_path / "build", 2.0 + 0.02 * len(lines) + 1.5 * seg.ticks.sum() / cfg.tick_hz)
    assert res.state == "done" and len(res.marks) == len(seg.ticks)
    got, want = chip_events(res.steps, res.marks, CLOCK_HZ // cfg.tick_hz), model_events(seg)
    assert len(want) > 10 and np.array_equal(got, want)
