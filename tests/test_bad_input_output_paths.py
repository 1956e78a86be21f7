"""Every command's output path (issue 25, part 6): an input file, an existing file, a directory
where a file goes, a path under a file. One line and exit 2 before anything is written; no
input file is ever overwritten. (synth-csv and export --arduino: tests/test_bad_input_dataloss.py.)"""

from __future__ import annotations

import pytest

from tests.bad_input import copy_run, fails, tiny_run  # noqa: F401 (fixture)
from tests.files.test_pick_state import L_PATH


@pytest.fixture
def run(tiny_run, tmp_path):  # noqa: F811
    return copy_run(tiny_run, tmp_path / "run")


@pytest.fixture
def toml(tiny_run, tmp_path):  # noqa: F811
    t = tmp_path / "tiny.toml"
    t.write_bytes((tiny_run.parent / "tiny.toml").read_bytes())
    return t


@pytest.mark.parametrize("command", ["run", "generate", "train", "search"])
def test_outdir_is_the_scenario(toml, tmp_path, capsys, command):
    fails(capsys, [command, toml, "-o", toml], "exists and is not a directory", watch=tmp_path)


@pytest.mark.parametrize("command", ["run", "generate", "train", "search"])
def test_outdir_under_the_scenario(toml, tmp_path, capsys, command):
    fails(capsys, [command, toml, "-o", toml / "out"], f"{toml} is a file", watch=tmp_path)


@pytest.mark.parametrize("name", ["metrics.json", "model.pt", "data.npz"])
def test_report_outdir_is_an_input(run, capsys, name):
    fails(capsys, ["report", run, "-o", run / name], "exists and is not a directory", watch=run)


def test_report_outdir_under_an_input(run, capsys):
    fails(capsys, ["report", run, "-o", run / "metrics.json" / "report"], "is a file", watch=run)


@pytest.mark.parametrize("argv", [["evaluate"], ["export"], ["select"], ["verify"], ["estimate", "--target", "avr"],
                                  ["report"], ["search", "--trials", "1"], ["job", L_PATH, "--no-chip"]],
                         ids=lambda a: a[0])
@pytest.mark.parametrize("where", ["a_file", "under_a_file"])
def test_model_dir_that_is_no_directory(run, tmp_path, capsys, argv, where):
    f = run / "metrics.json"
    d = f if where == "a_file" else f / "deeper"
    fails(capsys, [argv[0], d, *argv[1:]], watch=tmp_path)


@pytest.mark.parametrize("name", ["metrics.json", "model.pt", "data.npz"])
def test_search_storage_is_an_input(run, capsys, name):
    fails(capsys, ["search", run, "--trials", "1", "--storage", f"journal://{run / name}"], "is not an Optuna journal",
          watch=run)


def test_search_storage_is_the_scenario(run, toml, tmp_path, capsys):
    fails(capsys, ["search", run, "--trials", "1", "--storage", f"journal://{toml}"], "is not an Optuna journal",
          watch=tmp_path)


def test_tanh_writes_nothing_where_it_runs(tmp_path, monkeypatch, capsys):
    from nnik.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["tanh"]) == 0
    assert list(tmp_path.iterdir()) == []
