"""kill -9 at random points: `nnik run`, `nnik select`, `nnik search` and `nnik export` are
killed after a delay the test draws (seeded, so a failure can be replayed), and afterwards
neither `nnik job` nor `nnik export --arduino` delivers anything the target rules out: each
either refuses in one line (exit 2) or delivers a finished pick that meets the target of the
model in the directory, whose C is byte for byte the C that was verified.

The killed `nnik run` starts over in a directory that holds a finished pick for max_error 0.1
(an 8x8 table at 0.078) with a newer scenario whose max_error 0.06 rules that pick out."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from nnik.files import pick_state
from nnik.files.c_hash import dir_hash
from nnik.cli import main
from nnik.errors import NnikError
from tests.pick_fixtures import RUN_SECONDS, copy_picked, picked_run, tiny_pick_toml  # noqa: F401 (fixture)
from tests.files.test_pick_state import NAME, deliveries

POINTS = {"run": 2, "select": 2, "search": 2, "export": 2}
NEWER_TARGET = 0.06


def argv_for(command: str, run: Path, tmp: Path) -> list[str]:
    if command == "run":
        toml = tmp / "newer.toml"
        toml.write_text(tiny_pick_toml(NEWER_TARGET))
        return ["run", str(toml), "-o", str(run)]
    if command == "select":
        return ["select", str(run)]
    if command == "search":
        return ["search", str(run), "--trials", "8", "--families", "lut,poly"]
    return ["export", str(run), "--arduino", str(tmp / "lib_killed")]


def kill_after(argv: list[str], delay: float) -> str:
    """Run `python -m nnik argv`, SIGKILL its whole process group after `delay` seconds (unless
    it ended first); returns what happened."""
    p = subprocess.Popen([sys.executable, "-m", "nnik", *argv], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True)
    try:
        rc = p.wait(timeout=delay)
        return f"ended by itself (exit {rc})"
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        return "killed"


def model_target(run: Path) -> dict | None:
    """The [target] of the model now in the directory (None if model.pt is unreadable)."""
    from nnik.implementations.mlp.train import TrainedModel

    try:
        return TrainedModel.load(run / "model.pt").scenario.target
    except NnikError:
        return None


def assert_nothing_ruled_out_is_delivered(run: Path, lib: Path, capsys) -> str:
    target = model_target(run)
    outcomes = []
    for argv in deliveries(run, lib):
        capsys.readouterr()
        rc = main([str(a) for a in argv])
        err = capsys.readouterr().err
        if rc == 2:
            lines = err.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith("nnik: error: "), err
            if not (run / pick_state.PICK_FILE).exists():
                assert f"nnik select {run}" in lines[0], lines[0]
            outcomes.append("refused")
            continue
        assert rc == 0, err
        st = pick_state.status(run)
        assert st.ok and target is not None, st.message
        m = st.marker
        assert m["pre_max"] <= target["max_error"], (m["pre_max"], target)
        res = st.check(target["chip"])
        assert res["bit_exact"] and st.check("host")["bit_exact"]
        assert not target.get("max_cycles") or res["cycles"] <= target["max_cycles"]
        assert not target.get("max_flash_bytes") or res["flash_bytes"] <= target["max_flash_bytes"]
        assert st.disk_hash == m["c_hash"] == dir_hash(run / "c", NAME)
        if argv[0] == "export":
            assert dir_hash(lib / "src", NAME) == m["c_hash"]
        outcomes.append("delivered")
    return "/".join(outcomes)


@pytest.mark.parametrize("command", list(POINTS))
def test_killed_command_never_leads_to_a_delivery_the_target_rules_out(picked_run, tmp_path, capsys, command):
    rng = random.Random(f"nnik-kill-{command}")
    whole = RUN_SECONDS.get("run", 60.0)  # the uninterrupted tiny run: every command fits in it
    span = {"run": (0.5, whole), "select": (2.0, 0.8 * whole), "search": (2.0, 0.8 * whole), "export": (1.0, 15.0)}
    seen = []
    for i in range(POINTS[command]):
        run = copy_picked(picked_run, tmp_path / f"run{i}")
        delay = rng.uniform(*span[command])
        what = kill_after(argv_for(command, run, tmp_path), delay)
        seen.append((round(delay, 1), what, assert_nothing_ruled_out_is_delivered(run, tmp_path / f"lib{i}", capsys)))
    print(command, seen)
