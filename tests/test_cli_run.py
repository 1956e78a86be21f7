"""`nnik run` end to end on a small scenario: every stage runs and leaves its artefacts."""

from __future__ import annotations

import json

from nnik.cli import main
from tests.conftest import DATASETS, write_toml


def test_run_end_to_end(tmp_path, capsys):
    text = (DATASETS / "galvo_cba2012.toml").read_text()
    text = text.replace("n_train = 1000", "n_train = 300").replace("n_test = 20000", "n_test = 2000")
    text = text.replace("max_seconds = 60", "max_seconds = 4\nrestarts = 1\nadam_steps = 500")
    toml = write_toml(tmp_path, text)
    out = tmp_path / "out"
    assert main(["run", str(toml), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
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
    text = text.replace("max_seconds = 60", "max_seconds = 20\nrestarts = 2\nadam_steps = 200\nlbfgs_rounds = 5")
    toml = write_toml(tmp_path, text)
    out = tmp_path / "out"
    for cmd in (["generate", toml, "-o", out], ["train", toml, "-o", out]):
        r = subprocess.run([sys.executable, "-m", "nnik", *map(str, cmd)], capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        assert "\r" not in r.stdout + r.stderr
    assert (out / "model.pt").is_file()
