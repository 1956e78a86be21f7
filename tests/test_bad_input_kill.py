"""SIGINT and SIGKILL in the middle of a write (issue 25, part 6): each command is started as a
subprocess and killed the moment a temporary file of one of its atomic writes exists. Then no
output a later command trusts is torn (SIGINT also leaves no temporary file), the lock went with
the process, and a rerun in the same directory succeeds with the result of an uninterrupted run."""

from __future__ import annotations

import json
import shutil
import signal

import numpy as np
import pytest

from tests.bad_input import tiny_run  # noqa: F401 (fixture)
from tests.bad_input_os import kill_during, leftovers, nnik, snapshot, torn_files
from tests.pick_fixtures import picked_run  # noqa: F401 (fixture)
from tests.test_bad_input_disk import COMMANDS, _setup


def _arrays(path):
    with np.load(path) as z:
        return {k: z[k].tolist() for k in z.files}


def _state(path):
    import torch

    blob = torch.load(path, weights_only=True)
    return {k: v.tolist() for k, v in blob["state_dict"].items()}


RESULT = {  # what an uninterrupted run gives, to compare the rerun with
    "generate": lambda r: _arrays(r / "data.npz"),
    "train": lambda r: _state(r / "model.pt"),
    "export": lambda r: snapshot(r / "c"),
    "report": lambda r: sorted(p.name for p in (r / "report").iterdir()),
    "synth-csv": lambda r: (r / "marks.csv").read_bytes(),
    "job": lambda r: json.loads((r / "job" / "l_path.json").read_text())["contour_um"],
    "export --arduino": lambda r: snapshot(r / "lib"),
}


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL], ids=["SIGINT", "SIGKILL"])
@pytest.mark.parametrize("command", list(RESULT))
def test_killed_in_a_write_then_rerun(tiny_run, request, tmp_path, command, sig):  # noqa: F811
    kind, argv = COMMANDS[command]
    ref, toml = _setup(kind, tiny_run, request, tmp_path / "ref")
    run = tmp_path / "run"
    shutil.copytree(ref, run)
    proc = nnik(argv(ref, toml, tmp_path))
    assert proc.returncode == 0, proc.stderr[-2000:]
    before = snapshot(run)
    what = kill_during(argv(run, toml, tmp_path), sig, lambda: bool(leftovers(run)))
    print(command, sig.name, what)
    if sig == signal.SIGINT:
        assert leftovers(run) == []  # an interrupted atomic write cleans up after itself
    temp = set(leftovers(run))  # SIGKILL: a hidden temporary file may stay; nothing reads it
    assert [f for f in torn_files(run, before) if f not in temp and not any(f.startswith(t + "/") for t in temp)] == []
    proc = nnik(argv(run, toml, tmp_path))  # the lock died with the process: the rerun is not refused
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert RESULT[command](run) == RESULT[command](ref)
