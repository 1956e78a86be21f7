"""The library on the simulated Uno: Arduino AVR core + simavr. The self-test passes, the G-code
firmware fits, and every step it emits for each shipped job equals the Python model's."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from nnik import pipeline
from nnik.arduino_export import export_arduino
from nnik.gcode import chip
from nnik.gcode.job import run_job
from nnik.gcode.motion import interpret
from tests.conftest import require_tool

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"


@pytest.fixture(autouse=True)
def toolchain():
    for tool in ("avr-gcc", "avr-g++", "simavr"):
        require_tool(tool)
    why = chip.tool_missing_reason()
    if why:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(why)
        pytest.skip(why)


@pytest.fixture(scope="module")
def models(galvo_run, corexy_run):
    for out in (galvo_run, corexy_run):
        pipeline.export(out)
    return {"galvo_cba2012": galvo_run, "corexy_nonlinear": corexy_run}


@pytest.mark.parametrize("scenario", ["galvo_cba2012", "corexy_nonlinear"])
@pytest.mark.parametrize("job", ["l_path", "circle", "star"])
def test_every_step_of_every_job_matches(models, scenario, job):
    res = run_job(models[scenario], JOBS / f"{job}.gcode", use_chip=True)
    c = res["chip"]
    assert c["selftest_pass"], c["selftest"]
    assert c["state"] == "done"
    assert c["steps_equal"] and c["steps"] == res["steps"] > 0
    assert c["replies_equal"] and set(c["replies"]) == {"ok"}
    assert c["segments_started"] == res["segments"]
    assert c["flash_bytes"] <= chip.FLASH_BYTES and c["ram_bytes"] <= chip.RAM_BYTES - 512  # stack room
    assert 0 < c["cycles_per_segment"]["mean"] <= c["cycles_per_segment"]["max"] < 20000
    assert Path(res["png"]).stat().st_size > 10_000
    assert res["contour_um"]["max"] >= res["chord_um"]["max"]


def test_bad_lines_get_the_same_error_on_the_chip(models, tmp_path):
    out = models["corexy_nonlinear"]
    lines = ["G1 X1 F3000", "G1 Z2", "G2 X5 Y5 I1", "G1 X" + "1" * 100, "G7", "G1 X1.1234567", "G1 Y1", "M400"]
    lib = export_arduino(out, tmp_path / "lib")
    fw = chip.build_sketch(tmp_path / "lib", f"{lib['name']}_gcode", tmp_path / "build")
    run = chip.run_firmware(fw, lines, tmp_path / "build", 5.0)
    got = [t for _, t in run.replies if not t.startswith("nnik ")]
    want = interpret(lines, lib["machine"]).replies
    assert got == want
    assert want[1] == "error: line 2: unsupported word Z" and want[3] == "error: line 4: line too long"
    assert sum(r.startswith("error:") for r in want) == 5
