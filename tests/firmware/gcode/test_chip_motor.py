"""Chip = model with motor limits (issue 26 item 1): a shipped job on the simulated Uno built with
[motion] motor limits that bind matches the Python model step for step (run_both)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from nnik.firmware.config import default_machine
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.ik_oracle import load_scenario_of
from nnik.machine.motor_limits import motor_rows
from tests.firmware.gcode.conftest import run_both

ROOT = Path(__file__).resolve().parents[3]
LIMITS = {"motor_max_speed": [5000.0, 5000.0], "motor_max_accel": [120000.0, 120000.0]}  # microsteps


def test_motor_limited_star_job_chip_equals_model(tool_firmware, corexy_run):
    scn = load_scenario_of(corexy_run)
    base = replace(default_machine(scn), bounds_um=None, features=frozenset())  # star.gcode's own build, as `nnik job` makes it
    rows, vc = motor_rows(scn.mechanism, scn.actuator, scn.workspace, {**scn.motion, **LIMITS}, scn.source)
    cfg = replace(base, motor_rows=rows, motor_vc_um_s=vc)
    lines = (ROOT / "datasets" / "jobs" / "star.gcode").read_text().splitlines()
    plan, seg, res = run_both(tool_firmware(cfg), lines)
    free = plan_steps(interpret(lines, base), base, tool_firmware(cfg)[3])
    assert seg.ticks.sum() > free.ticks.sum()  # the limits bind: the job takes longer
