"""Issue 25's data-loss findings and output-side tracebacks, each kept fixed: no command writes
over one of its inputs, a refusal changes nothing, an output that is a directory, a file or under
a file gets one line and exit 2."""

from __future__ import annotations

import json

import pytest

from nnik.cli import main
from nnik.files import pick_state
from tests.bad_input import GALVO, copy_run, fails, snapshot, tiny_run, with_training  # noqa: F401 (fixture)
from tests.conftest import write_toml
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)
from tests.files.test_pick_state import L_PATH


@pytest.fixture
def scenario(tmp_path):
    return write_toml(tmp_path, with_training(GALVO))


# ---- synth-csv -----------------------------------------------------------------------------------
@pytest.mark.parametrize("spelling", ["same", "relative", "dotted"])
def test_synth_csv_never_writes_over_its_scenario(scenario, tmp_path, capsys, monkeypatch, spelling):
    monkeypatch.chdir(tmp_path)
    out = {"same": scenario, "relative": scenario.name, "dotted": f"./sub/../{scenario.name}"}[spelling]
    (tmp_path / "sub").mkdir()
    fails(capsys, ["synth-csv", scenario, "-o", out, "-n", 30], "is an input of this command", watch=tmp_path)


def test_synth_csv_never_writes_over_a_link_to_its_scenario(scenario, tmp_path, capsys):
    link = tmp_path / "link.csv"
    link.symlink_to(scenario)
    fails(capsys, ["synth-csv", scenario, "-o", link, "-n", 30], "is an input of this command", watch=tmp_path)


def test_synth_csv_into_a_directory(scenario, tmp_path, capsys):
    (tmp_path / "d").mkdir()
    fails(capsys, ["synth-csv", scenario, "-o", tmp_path / "d", "-n", 30], "is a directory", watch=tmp_path)


def test_synth_csv_under_a_file(scenario, tmp_path, capsys):
    fails(capsys, ["synth-csv", scenario, "-o", scenario / "x.csv", "-n", 30], f"{scenario} is a file",
          watch=tmp_path)


@pytest.mark.parametrize("seed", ["-1", str(2**32)])
def test_synth_csv_seed_out_of_range(scenario, tmp_path, capsys, seed):
    fails(capsys, ["synth-csv", scenario, "-o", tmp_path / "m.csv", "-n", 30, "--seed", seed], "--seed",
          "must be in [0, 4294967295]", watch=tmp_path)


def test_synth_csv_replaces_an_existing_csv_whole(scenario, tmp_path, capsys):
    out = tmp_path / "m.csv"
    out.write_text("old\n")
    assert main(["synth-csv", str(scenario), "-o", str(out), "-n", "30"]) == 0
    text = out.read_text()
    assert text.startswith("x_um,y_um,q1,q2") and len(text.splitlines()) == 31
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


# ---- evaluate and select keep a verified pick ------------------------------------------------------
def test_evaluate_on_a_finished_run_keeps_the_selection_and_the_pick(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    before = json.loads((run / "metrics.json").read_text())
    assert pick_state.status(run).ok
    assert main(["evaluate", str(run)]) == 0
    after = json.loads((run / "metrics.json").read_text())
    assert after["selection"] == before["selection"] and (run / "pick.json").is_file()
    assert after["float"] == before["float"]
    assert pick_state.status(run).ok


def test_evaluate_after_new_training_drops_the_old_pick(picked_run, tmp_path):
    """The other side: a model.pt that is not the one the pick was made from takes the pick away."""
    run = copy_picked(picked_run, tmp_path / "run")
    import torch

    from nnik.implementations.mlp.train import TrainedModel

    m = TrainedModel.load(run / "model.pt")
    with torch.no_grad():
        next(m.net.parameters()).view(-1)[0] += 1e-9  # other weights: another model as far as the pick knows
    m.save(run / "model.pt")
    assert main(["evaluate", str(run)]) == 0
    assert not (run / "pick.json").exists() and "selection" not in json.loads((run / "metrics.json").read_text())


@pytest.mark.parametrize("option,value,needle", [
    ("--max-cycles", "-1", "--max-cycles: must be > 0"),
    ("--max-flash-bytes", "0", "--max-flash-bytes: must be > 0"),
    ("--max-error", "inf", "--max-error: must be a finite number"),
])
def test_select_refusing_a_limit_changes_nothing(picked_run, tmp_path, capsys, option, value, needle):
    run = copy_picked(picked_run, tmp_path / "run")
    fails(capsys, ["select", run, option, value], needle, watch=run)
    assert pick_state.status(run).ok


# ---- export --arduino ----------------------------------------------------------------------------
def test_arduino_into_an_existing_file(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    f = tmp_path / "mine.txt"
    f.write_text("keep me\n")
    fails(capsys, ["export", run, "--arduino", f], "exists and is not a folder", watch=tmp_path)


def test_arduino_under_a_file(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    f = tmp_path / "mine.txt"
    f.write_text("keep me\n")
    fails(capsys, ["export", run, "--arduino", f / "lib"], f"{f} is a file", watch=tmp_path)


@pytest.mark.parametrize("where", ["model_dir", "its_parent", "a_users_folder"])
def test_arduino_never_replaces_a_folder_it_did_not_write(picked_run, tmp_path, capsys, where):
    run = copy_picked(picked_run, tmp_path / "run")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me\n")
    target = {"model_dir": run, "its_parent": tmp_path, "a_users_folder": mine}[where]
    fails(capsys, ["export", run, "--arduino", target], "give a new folder", watch=tmp_path)


def test_arduino_replaces_its_own_earlier_library_whole(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    lib = tmp_path / "lib"
    assert main(["export", str(run), "--arduino", str(lib)]) == 0
    first = snapshot(lib)
    (lib / "src" / "stale_from_another_machine.h").write_text("#error stale\n")
    assert main(["export", str(run), "--arduino", str(lib)]) == 0
    assert snapshot(lib) == first  # the stale file is gone, everything else byte for byte the same
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]


# ---- job -----------------------------------------------------------------------------------------
def test_job_dir_is_a_file(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    (run / "job").write_text("not a directory\n")
    fails(capsys, ["job", run, L_PATH, "--no-chip"], "is a file where nnik writes the directory job/", watch=run)


def test_job_never_writes_over_its_gcode(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    (run / "job").mkdir()
    gcode = run / "job" / "l_path.json"
    gcode.write_bytes(L_PATH.read_bytes())
    fails(capsys, ["job", run, gcode, "--no-chip"], "is a file the job writes", watch=run)
