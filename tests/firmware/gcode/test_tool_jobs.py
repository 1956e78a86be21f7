"""Jobs in the style of the tools users bring (datasets/jobs/: issue 20's grbl CAM/laser and pen
plotter jobs, Inkscape's gcodetools, LaserGRBL, LightBurn's grbl output, a Fusion 360 grbl post,
a slicer's XY moves sent with Marlin checksums), each on the simulated Uno built for the tool it
names ('; nnik-machine:'): every answer, step and tool change equal to the Python model's."""

from __future__ import annotations

from pathlib import Path

import pytest

from nnik.firmware.config import default_machine
from nnik.firmware.gcode.job import job_machine, read_job, tool_report
from nnik.firmware.ik_oracle import load_scenario_of
from tests.firmware.gcode.conftest import run_both

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"

# job: (tool, the lines the firmware refuses, tool changes at least)
STYLES = {
    "grbl_cam_laser": ("laser", [], 4),
    "pen_plotter": ("pen", [], 4),  # down, up, down, up (up is D11 low, as at reset)
    "inkscape_gcodetools": ("servo", [], 5),
    "lasergrbl_raster": ("laser", [], 12),
    "lightburn_grbl": ("laser", [], 4),
    "fusion360_grbl": ("laser", [], 4),
    "slicer_xy": ("pen", [], 4),
}


@pytest.mark.parametrize("job", sorted(STYLES))
def test_tool_style_job_equal_on_the_chip(corexy_run, tool_firmware, job):
    tool, refused, min_changes = STYLES[job]
    lines = read_job(JOBS / f"{job}.gcode")
    cfg = job_machine(lines, default_machine(load_scenario_of(corexy_run)), job)
    assert cfg.tool == tool
    plan, seg, res = run_both(tool_firmware(cfg), lines)
    bad = [r for r in plan.replies if r != "ok"]
    assert bad == refused
    t = tool_report(seg, cfg)
    assert t["changes"] >= min_changes and len(res.tool) == t["changes"]
    assert t["on_mm"] > 20 and t["travel_mm"] > 5 and t["on_s"] > 0.5
