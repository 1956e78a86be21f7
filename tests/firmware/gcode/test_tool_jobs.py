"""Jobs in the style of the tools users bring (datasets/jobs/: issue 20's grbl CAM/laser and pen
plotter jobs, Inkscape's gcodetools, LaserGRBL, LightBurn's grbl output, a Fusion 360 grbl post,
a slicer's XY moves sent with Marlin checksums), each on the simulated Uno built for its tool
(`nnik job --tool`, --tool-z): every answer, step and tool change equal to the Python model's."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import pytest

from nnik.firmware.config import default_machine
from nnik.job.measure import tool_report
from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
from nnik.firmware.gcode.reader import sendable
from nnik.firmware.ik_oracle import load_scenario_of
from tests.firmware.gcode.conftest import run_both

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"

# job: (tool, Z at or below which it is down (mm), tool changes at least)
STYLES = {
    "grbl_cam_laser": ("laser", None, 4),
    "pen_plotter": ("pen", None, 4),  # down, up, down, up (up is D11 low, as at reset)
    "inkscape_gcodetools": ("servo", None, 5),
    "lasergrbl_raster": ("laser", None, 12),
    "lightburn_grbl": ("laser", None, 4),
    "fusion360_grbl": ("laser", None, 4),
    "slicer_xy": ("pen", 0.25, 4),
}


@pytest.mark.parametrize("job", sorted(STYLES))
def test_tool_style_job_equal_on_the_chip(corexy_run, tool_firmware, job):
    tool, z_mm, min_changes = STYLES[job]
    prep = prepare(read_job(JOBS / f"{job}.gcode"), default_machine(load_scenario_of(corexy_run)),
                   JobOptions(tool=tool, tool_z_mm=z_mm), job)
    cfg = prep.cfg
    assert cfg.tool == tool
    plan, seg, res = run_both(tool_firmware(cfg), [sendable(ln).decode() for ln in prep.lines])
    assert set(plan.replies) == {"ok"}
    t = tool_report(seg, cfg)
    assert t["changes"] >= min_changes and len(res.tool) == t["changes"]
    assert t["on_mm"] > 20 and t["travel_mm"] > 5 and t["on_s"] > 0.5


@pytest.mark.parametrize("kind", ["zvd", "3hump_ei"])
@pytest.mark.parametrize("job", ["lasergrbl_raster", "grbl_cam_laser", "lightburn_grbl"])
def test_shaped_laser_jobs_equal_on_the_chip(corexy_run, tool_firmware, kind, job):
    """With a shaper the tool follows the shaped head (nnik_sh_tool, M4 scaled by the shaped
    speed): every tool change and step on the chip equals the model's, and the tool comes on
    later than the planner's switch (it did not before)."""
    from dataclasses import replace

    from nnik.firmware.config import shaper_taps
    from nnik.firmware.gcode.steps import model_tool_events

    base = default_machine(load_scenario_of(corexy_run))
    dyn = {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)}
    cfg = replace(prepare(read_job(JOBS / f"{job}.gcode"), base, JobOptions(tool="laser"), job).cfg, shaper=kind,
                  shaper_taps=shaper_taps(kind, dyn, base.sample_hz), bounds_um=None)
    prep = prepare(read_job(JOBS / f"{job}.gcode"), cfg, JobOptions(tool="laser"), job)
    plan, seg, res = run_both(tool_firmware(prep.cfg), [sendable(ln).decode() for ln in prep.lines])
    assert set(plan.replies) == {"ok"} and len(res.tool) == len(model_tool_events(seg)) >= 4
    first_on = int(np.flatnonzero(seg.duty > 0)[0])
    assert first_on > int(np.flatnonzero((seg.block >= 0) & (np.asarray(plan.tool)[np.maximum(seg.block, 0)] & 0xFF > 0)
                                         & (seg.duty >= 0))[0])
