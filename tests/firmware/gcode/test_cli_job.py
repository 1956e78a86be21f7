"""`nnik job` and `nnik export --arduino` from the command line."""

from __future__ import annotations

import json
from pathlib import Path

from nnik.cli import main
from tests.pick_fixtures import picked_run  # noqa: F401 (fixture: a finished, verified pick; job and export need one)

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


def test_bad_gcode_is_one_line_naming_it_and_exit_2(picked_run, tmp_path, capsys):
    bad = tmp_path / "bad.gcode"
    bad.write_text("G21\nG1 X1 Z2\n")
    assert main(["job", str(picked_run), str(bad), "--no-chip"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"nnik: error: {bad}: line 2: unsupported word Z"
    assert main(["job", str(picked_run), str(tmp_path / "missing.gcode"), "--no-chip"]) == 2
    assert main(["job", str(picked_run), str(JOBS / "l_path.gcode"), "--seg-um", "50", "--no-chip"]) == 2


def test_job_python_only_writes_figures_and_plot(picked_run, capsys):
    assert main(["job", str(picked_run), str(JOBS / "l_path.gcode"), "--no-chip"]) == 0
    res = json.loads((picked_run / "job" / "l_path.json").read_text())
    assert res["segments"] == 40 and res["chip"] == {"not_run": "not asked"}
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
