"""`nnik job SCENARIO.toml JOB -o MODEL_DIR`: the scenario must be the model's machine (another
machine's TOML used to run silently on this model), and its [motion] is the truth (an edited
[motion] used to be ignored for the copy inside model.pt)."""

from __future__ import annotations

import json
from pathlib import Path

from nnik.cli import main
from tests.bad_input import fails
from tests.conftest import DATASETS
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


def test_another_machines_scenario_is_refused_naming_both(picked_run, tmp_path, capsys):
    other = DATASETS / "galvo_dual_xy2.toml"
    fails(capsys, ["job", other, JOBS / "l_path.gcode", "-o", picked_run, "--no-chip"], "galvo_dual_xy2",
          "holds a model of machine 'galvo_cba2012'", str(picked_run), watch=picked_run)


def test_a_changed_machine_of_the_same_name_is_refused(picked_run, tmp_path, capsys):
    toml = tmp_path / "tiny.toml"
    toml.write_text((picked_run.parent / "tiny.toml").read_text().replace("n_train = 1000", "n_train = 900"))
    fails(capsys, ["job", toml, JOBS / "l_path.gcode", "-o", picked_run, "--no-chip"],
          "a changed machine of the same name", watch=picked_run)


def test_the_scenarios_edited_motion_is_used(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    toml = tmp_path / "tiny.toml"
    toml.write_text((picked_run.parent / "tiny.toml").read_text() + "\n[motion]\nmax_feed_mm_min = 600.0\n"
                    "accel_x_mm_s2 = 200.0\n")
    job = JOBS / "l_path.gcode"
    assert main(["job", str(run), str(job), "--no-chip"]) == 0
    as_trained = json.loads((run / "job" / "l_path.json").read_text())["motion"]
    capsys.readouterr()
    assert main(["job", str(toml), str(job), "-o", str(run), "--no-chip"]) == 0
    assert "[motion] from" in capsys.readouterr().out
    edited = json.loads((run / "job" / "l_path.json").read_text())["motion"]
    assert as_trained["max_feed_mm_min"] == 3000.0 and as_trained["accel_mm_s2"][0] == 1000.0
    assert edited["max_feed_mm_min"] == 600.0 and edited["accel_mm_s2"][0] == 200.0
    assert edited["job_s"] > as_trained["job_s"]
