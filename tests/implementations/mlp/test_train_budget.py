"""Training is budgeted in iterations; the wall clock is a safety net that is recorded and
announced when it fires (issue 11, section 4)."""

from __future__ import annotations

import json

import torch

from nnik.cli import main
from nnik.machine.data import build_dataset
from nnik.machine.scenario import load_scenario
from nnik.implementations.mlp.train import train_model
from tests.bad_input import GALVO, with_training
from tests.conftest import write_toml


def test_same_seed_same_budget_same_model(tmp_path):
    scn = load_scenario(write_toml(tmp_path, with_training(
        GALVO, "[training]\nadam_steps = 150\nlbfgs_rounds = 4\nrestarts = 2\n")))
    ds = build_dataset(scn)
    a = train_model(scn, ds, progress=False)
    b = train_model(scn, ds, progress=False)
    assert a.stopped_by == b.stopped_by == "budget"
    sa, sb = a.net.state_dict(), b.net.state_dict()
    for k in sa:
        assert torch.equal(sa[k], sb[k]), k
    assert [h["val"] for h in a.history] == [h["val"] for h in b.history]


def test_wall_clock_cap_is_recorded_and_announced(tmp_path, capsys):
    toml = write_toml(tmp_path, with_training(
        GALVO.replace("n_test = 20000", "n_test = 200"),
        "[training]\nmax_seconds = 0.001\nadam_steps = 100000\nrestarts = 3\n"))
    out = tmp_path / "out"
    assert main(["generate", str(toml), "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["train", str(toml), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert "warning" in said and "wall-clock" in said and "max_seconds" in said
    assert main(["evaluate", str(out)]) == 0
    training = json.loads((out / "metrics.json").read_text())["training"]
    assert training["stopped_by"] == "wall_clock"
    assert training["restarts_run"] == 1  # the cap also skipped the remaining restarts
