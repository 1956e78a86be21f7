"""`nnik run` end to end on a small scenario: every stage runs and leaves its artefacts, and a
scenario's max_error reaches the pick through few modules."""

from __future__ import annotations

import contextlib
import io
import json
import sys

import pytest

from nnik.cli import main
from tests.bad_input import with_training
from tests.conftest import DATASETS, write_toml

MAX_MODULES = 6  # issue 17: following a scenario's max_error from the CLI to the pick crosses at most this many


@pytest.fixture(scope="module")
def traced_run(tmp_path_factory):
    """`nnik run` on a small galvo, traced: at every call of Candidate.meets (where a candidate's
    error is compared with max_error) and of the MLP's train_model, the call stack (and the
    max_error given) is recorded.
    Returns (outdir, printed output, the recorded calls, the scenario file)."""
    from nnik.implementations.mlp.train import train_model
    from nnik.selection import Candidate

    tmp_path = tmp_path_factory.mktemp("run")
    text = (DATASETS / "galvo_cba2012.toml").read_text()
    text = text.replace("n_train = 1000", "n_train = 300").replace("n_test = 20000", "n_test = 2000")
    text = with_training(text, "[training]\nrestarts = 1\nadam_steps = 500\n")
    toml = write_toml(tmp_path, text)
    out = tmp_path / "out"
    meets, train, calls = Candidate.meets.__code__, train_model.__code__, []

    def tracer(frame, event, arg):  # called on each Python call; None: no line events anywhere
        if frame.f_code is meets or frame.f_code is train:
            stack, f = [], frame
            while f is not None:
                stack.append((f.f_globals.get("__name__", ""), f.f_code.co_name))
                f = f.f_back
            calls.append({"max_error": frame.f_locals.get("max_error"), "stack": stack[::-1]})
        return None

    printed = io.StringIO()
    before = sys.gettrace()
    sys.settrace(tracer)
    try:
        with contextlib.redirect_stdout(printed):
            rc = main(["run", str(toml), "-o", str(out)])
    finally:
        sys.settrace(before)
    assert rc == 0
    return out, printed.getvalue(), calls, toml


def test_run_end_to_end(traced_run):
    out, printed, calls, _ = traced_run
    # one pipeline: the MLP trains once, as its family's fit inside the ladder like every family
    trainings = [c["stack"] for c in calls if c["stack"][-1][1] == "train_model"]
    assert len(trainings) == 1
    assert ("nnik.selection", "fit_ladder") in trainings[0] and ("nnik.implementations.mlp.family", "fit") in trainings[0]
    for f in ("data.npz", "model.pt", "model.onnx", "metrics.json", "c/galvo_cba2012.c", "c/galvo_cba2012.h",
              "c/galvo_cba2012_float.c", "report/index.html", "report/report.md"):
        assert (out / f).is_file(), f
    assert not (out / "c" / "galvo_cba2012_lut.c").exists()  # the old LUT baseline retired
    m = json.loads((out / "metrics.json").read_text())
    for key in ("name", "outputs", "unit", "float", "train_seconds", "fixed", "host", "baselines", "targets"):
        assert key in m, key
    assert m["host"]["mismatches"] == 0
    for target in ("avr", "pic18"):
        t = m["targets"][target]
        assert "not_run" in t or t["mismatches"] == 0
    # the pick leads: its line comes before the families table and the summary, and the summary's
    # per-chip rows are the pick's figures, not the MLP's
    pick = next(r for r in m["selection"]["implementations"] if r["picked"])
    assert printed.index("pick:") < printed.index("every family's best") < printed.index("report:")
    from nnik.report import summary_rows

    rows = summary_rows(m)
    assert rows[0][0] == "pick (c/NAME.c)" and rows[0][1].startswith(pick["family"])
    chips = {r[0]: r for r in rows}
    for target in ("avr", "pic18"):
        assert chips[target][1].startswith(f"{pick['cycles'][target]:.0f} cycles")
        assert f"flash {pick['flash_bytes'][target]} B" in chips[target][2]
        assert chips[f"mlp on {target}"][1].startswith(f"{m['targets'][target]['cycles']:.0f} cycles")


def test_no_progress_bars_in_a_log(tmp_path):
    """Issue 16: with stderr not a terminal (a log, a pipe, CI), training writes no carriage-return
    bar updates, so an error line can never land on a bar's line."""
    import subprocess
    import sys

    text = (DATASETS / "galvo_cba2012.toml").read_text().replace("n_test = 20000", "n_test = 300")
    text = with_training(text, "[training]\nrestarts = 2\nadam_steps = 200\nlbfgs_rounds = 5\n")
    toml = write_toml(tmp_path, text)
    out = tmp_path / "out"
    for cmd in (["generate", toml, "-o", out], ["train", toml, "-o", out]):
        r = subprocess.run([sys.executable, "-m", "nnik", *map(str, cmd)], capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        assert "\r" not in r.stdout + r.stderr
    assert (out / "model.pt").is_file()


def test_max_error_reaches_the_pick_through_at_most_6_modules(traced_run):
    """Issue 17's goal: where the pick is decided (selection.choose comparing each verified family
    best's error with max_error), the stack from the CLI down crosses at most MAX_MODULES nnik
    modules, and the max_error compared is the scenario's."""
    from nnik.machine.scenario import load_scenario

    _, _, calls, toml = traced_run
    max_error = load_scenario(toml).target["max_error"]
    deciding = [c for c in calls if c["stack"][-1][1] == "meets"
                and any(m == "nnik.selection" and fn in ("choose", "choose_most_accurate") for m, fn in c["stack"])]
    assert deciding, "the pick never compared a candidate's error with max_error"
    for c in deciding:
        assert c["max_error"] == max_error
        mods = [m for m, _ in c["stack"] if m == "nnik" or m.startswith("nnik.")]
        assert mods[0] == "nnik.cli", mods
        chain = list(dict.fromkeys(mods))
        assert len(chain) <= MAX_MODULES, " -> ".join(chain)
