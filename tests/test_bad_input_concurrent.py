"""Two writers at once (issue 25, part 6): two `nnik run` on one output directory, two `nnik job`
on one model. The second is refused in one line naming the first's pid (the advisory lock,
nnik.files.outdir), the first finishes as if alone, and its lock goes with it."""

from __future__ import annotations

import os
import subprocess
import sys

from nnik.files import pick_state
from nnik.files.outdir import LOCK_FILE
from tests.bad_input import fails, tiny_run  # noqa: F401 (fixture)
from tests.bad_input_os import ROOT, wait_for
from tests.conftest import DATASETS, require_tool
from tests.files.test_pick_state import L_PATH
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)


def start(argv) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "nnik", *map(str, argv)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})


def holds_lock(d, pid: int) -> bool:
    try:
        return (d / LOCK_FILE).read_text().strip() == str(pid)
    except OSError:
        return False


def second_is_refused(first: subprocess.Popen, d, argv, capsys) -> None:
    """The second runs in this process (already started: it tries at once, while the first works)."""
    try:
        wait_for(lambda: holds_lock(d, first.pid) or first.poll() is not None, what="the first command's lock")
        assert first.poll() is None, "the first command ended before the second could start"
        fails(capsys, argv, "another nnik command", f"pid {first.pid}", "is writing into this directory")
    finally:
        _, err = first.communicate(timeout=900)
    assert first.returncode == 0, err[-2000:]
    assert not (d / LOCK_FILE).exists()


def test_two_runs_on_one_outdir(tiny_run, tmp_path, capsys):  # noqa: F811
    toml = tiny_run.parent / "tiny.toml"
    out = tmp_path / "out"
    first = start(["run", toml, "-o", out])
    second_is_refused(first, out, ["run", toml, "-o", out], capsys)
    assert pick_state.status(out).ok or (out / "metrics.json").is_file()  # the first run's result, whole


def test_two_jobs_on_one_model(picked_run, tmp_path, capsys):  # noqa: F811
    require_tool("simavr")
    run = copy_picked(picked_run, tmp_path / "run")
    first = start(["job", run, DATASETS / "jobs" / "star.gcode"])  # on the simulated chip: it takes a while
    second_is_refused(first, run, ["job", run, L_PATH, "--no-chip"], capsys)
    assert (run / "job" / "star.json").is_file() and not (run / "job" / "l_path.json").exists()
