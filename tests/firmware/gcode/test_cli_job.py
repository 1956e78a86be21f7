"""`nnik job` and `nnik export --arduino` from the command line."""

from __future__ import annotations

import json

import pytest
from pathlib import Path

from nnik.cli import main
from tests.pick_fixtures import picked_run  # noqa: F401 (fixture: a finished, verified pick; job and export need one)

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


def test_bad_gcode_is_one_line_naming_it_and_exit_2(picked_run, tmp_path, capsys):
    bad = tmp_path / "bad.gcode"
    bad.write_text("G21\nG1 X1 A2\n")
    assert main(["job", str(picked_run), str(bad), "--no-chip"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"nnik: error: {bad}:2: error:20 unsupported command: axis A: the machine has X and Y"
    assert main(["job", str(picked_run), str(tmp_path / "missing.gcode"), "--no-chip"]) == 2
    assert main(["job", str(picked_run), str(JOBS / "l_path.gcode"), "--seg-um", "50", "--no-chip"]) == 2
    capsys.readouterr()
    for shaper, msg in (("zvd", "needs a [dynamics] table"), ("auto", "needs a [dynamics] table"),
                        ("zvdd", "unknown shaper")):  # the galvo has no [dynamics]
        assert main(["job", str(picked_run), str(JOBS / "l_path.gcode"), "--shaper", shaper, "--no-chip"]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and msg in err and "--shaper" in err, err
    assert main(["job", str(picked_run), str(JOBS / "l_path.gcode"), "--precompensate", "--no-chip"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--precompensate" in err and "[dynamics]" in err, err


def test_job_python_only_writes_figures_and_plot(picked_run, capsys):
    assert main(["job", str(picked_run), str(JOBS / "l_path.gcode"), "--no-chip"]) == 0
    res = json.loads((picked_run / "job" / "l_path.json").read_text())
    assert res["chip"] == {"not_run": "not asked"}
    # two 10 mm legs at 20 mm/s: 1 s without acceleration; the ramps (1000 mm/s^2) and the slow
    # 90-degree corner (junction deviation 0.01 mm: ~5 mm/s) add tens of ms; a segment per 1 ms sample
    m = res["motion"]
    assert 1.0 < m["job_s"] < 1.1 and res["segments"] == m["samples"] == round(m["job_s"] * 1000)
    assert m["overspeed_samples"] == 0 and m["peak_speed_mm_s"] == pytest.approx(20.0, abs=0.01)
    # one microstep of this galvo is ~1.2 mm at the target: the rounding dominates, and an IK
    # within 0.5 microstep before rounding delivers at most one microstep from the exact one
    assert 0 < res["rounding_um"]["max"] and res["contour_um"]["max"] <= res["rounding_um"]["max"] + 1200
    assert (picked_run / "job" / "l_path.png").stat().st_size > 10_000
    assert "contour max / RMS" in capsys.readouterr().out


def test_export_arduino_library_layout(picked_run, tmp_path):
    lib = tmp_path / "lib"
    assert main(["export", str(picked_run), "--arduino", str(lib)]) == 0
    props = dict(ln.split("=", 1) for ln in (lib / "library.properties").read_text().splitlines())
    assert props["name"] == "nnik_galvo_cba2012" and props["includes"] == "galvo_cba2012.h"
    assert json.loads((lib / "library.json").read_text())["platforms"] == "atmelavr"
    for f in ("galvo_cba2012.c", "galvo_cba2012.h", "nnik_flash.h", "nnik_gcode.c", "nnik_gcode_config.h"):
        assert (lib / "src" / f).is_file(), f
    st = (lib / "examples" / "galvo_cba2012_selftest" / "galvo_cba2012_selftest.ino").read_text()
    assert st.count("    { ") == 64
    assert (lib / "examples" / "galvo_cba2012_gcode" / "galvo_cba2012_gcode.ino").is_file()


def test_job_with_a_tool_reports_it_and_checks_its_changes_on_the_chip(picked_run, capsys):
    """A LightBurn-style laser job through `nnik job` on the simulated Uno: the tool's changes
    equal the model's, the JSON and the table give tool-on and travel length and on-time."""
    from tests.firmware.gcode.conftest import require_chip

    require_chip()
    assert main(["job", str(picked_run), str(JOBS / "lightburn_grbl.gcode")]) == 0
    res = json.loads((picked_run / "job" / "lightburn_grbl.json").read_text())
    t, c = res["tool"], res["chip"]
    # 48 mm of rectangle and 4 x 4.24 mm of diamond with the laser on; the rest is G0 travel
    assert t["kind"] == "laser" and abs(t["on_mm"] - (40 + 4 * 18 ** 0.5)) < 0.1 and t["travel_mm"] > 10
    # M4: the power follows the planned speed, so every ramp and corner changes the duty (4 changes
    # without the planner); each change falls on the same segment and tick on the chip
    assert c["tool_equal"] and c["tool_changes"] == t["changes"] > 4 and c["steps_equal"]
    out = capsys.readouterr().out
    assert "tool on / travel" in out and f"{c['tool_changes']} equal" in out


def test_the_tool_is_the_machines_not_the_files(picked_run, tmp_path, capsys):
    """A comment does not change the machine (Z is a laser's focus); --tool and --tool-z do."""
    job = tmp_path / "pen.gcode"
    job.write_text("; nnik-machine: tool=pen pen_z_um=500\nG0 Z1\nG0 X1\nG1 Z0.4 F600\nG1 X2\nG0 Z1\n")
    assert main(["job", str(picked_run), str(job), "--no-chip"]) == 0
    res = json.loads((picked_run / "job" / "pen.json").read_text())
    assert res["machine"]["tool"] == "laser" and res["tool"]["on_mm"] == 0.0
    assert res["gcode"]["z_range_mm"] == [0.4, 1.0] and res["gcode"]["tool_rule"] == "s"
    assert main(["job", str(picked_run), str(job), "--no-chip", "--tool", "pen", "--tool-z", "0.5"]) == 0
    res = json.loads((picked_run / "job" / "pen.json").read_text())
    assert res["machine"]["tool"] == "pen" and res["tool"]["on_mm"] == 1.0 and res["tool"]["travel_mm"] == 1.0
    assert res["gcode"]["tool_rule"] == "z" and res["gcode"]["moves_tool_on"] == 1
    capsys.readouterr()
    assert main(["job", str(picked_run), str(job), "--no-chip", "--tool", "plasma"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("nnik: error: ") and "--tool" in err and "laser, pen, servo, spindle, knife, none" in err


def test_a_held_block_keeps_chip_equal_to_model_on_the_mega(picked_run):
    """On the ATmega2560 a block that finds the planner full is held back and its line answered at
    once (NNIK_GC_HOLD, nnik_gc_ahead): the planner sees the same pushes and samples in the same
    order, so a job with comments and tool moves between its blocks gives every step, reply and
    tool change the model's."""
    from nnik.job.open_loop import run_job
    from tests.firmware.gcode.conftest import require_chip

    require_chip()
    c = run_job(picked_run, JOBS / "inkscape_gcodetools.gcode", mcu="atmega2560")["chip"]
    assert c["steps_equal"] and c["replies_equal"] and c["tool_equal"], c
