"""`nnik job` as a user types it: relative paths from wherever they stand, a job that does not end
in M400, and -o with a model directory refused in one line."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

from nnik.machine.scenario import load_scenario
from tests.firmware.gcode.conftest import require_chip
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture: a finished, verified pick)

OPEN_JOB = "G21 G90 F3000\nG1 X2 Y1\nG2 X4 Y1 R1\nG1 X2\n"  # no M400: the last segments are still queued


def nnik(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "nnik", *args], cwd=cwd, capture_output=True, text=True, timeout=900)


def check_chip_equal(model: Path) -> dict:
    res = json.loads((model / "job" / "open.json").read_text())
    c = res["chip"]
    assert c["selftest_pass"] and c["steps_equal"] and c["replies_equal"], c
    assert c["segments_started"] == res["segments"] > 10
    # first tick to last tick on the chip: the model's ticks less one (the queue never ran dry)
    tick_s = 1 / res["machine"]["tick_hz"]
    assert abs(c["motion_s"] - (res["seconds"] - tick_s)) < 200 / 16e6 and c["end_s"] > c["motion_s"]
    return res


def test_job_with_relative_paths_from_other_directories(picked_run, tmp_path):
    require_chip()
    root = tmp_path / "caller"
    (root / "jobs").mkdir(parents=True)
    (root / "jobs" / "open.gcode").write_text(OPEN_JOB)
    shutil.copy(picked_run.parent / "tiny.toml", root / "tiny.toml")
    scenario = load_scenario(root / "tiny.toml").name
    model = copy_picked(picked_run, root / "build" / scenario)  # where `nnik job tiny.toml ...` looks

    # a scenario TOML and its default build dir, from the caller's root
    r = nnik(root, "job", "tiny.toml", "jobs/open.gcode")
    assert r.returncode == 0, r.stderr
    check_chip_equal(model)
    (model / "job" / "open.json").unlink()
    # a relative model directory, from a sibling directory
    r = nnik(root / "jobs", "job", f"../build/{scenario}", "open.gcode")
    assert r.returncode == 0, r.stderr
    res = check_chip_equal(model)
    assert "simulated chip: " in r.stdout and "idle at" in r.stdout
    assert (root / "jobs" / res["png"]).is_file()  # written where the caller's relative path says
    # the TOML with -o, relative, without the chip
    r = nnik(root / "jobs", "job", "../tiny.toml", "open.gcode", "-o", f"../build/{scenario}", "--no-chip")
    assert r.returncode == 0, r.stderr
    # -o beside a model directory: one line, exit 2
    r = nnik(root / "jobs", "job", f"../build/{scenario}", "open.gcode", "-o", "elsewhere")
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert r.stderr.startswith("nnik: error: elsewhere: -o: ") and "already a model directory" in r.stderr
