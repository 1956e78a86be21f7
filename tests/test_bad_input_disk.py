"""A full disk for every command (issue 25, part 6): real OS errors, not mocks. Unprivileged, a
file-size limit (RLIMIT_FSIZE: a write past it fails with EFBIG, the compilers nnik starts are
stopped by SIGXFSZ); as root, also a small tmpfs filled up (ENOSPC). Either way: exit 0 if the
outputs fit, else one `nnik: error:` line and exit 2, no temporary file left and no output file
torn (every file that changed is whole, so a later command never trusts half of one)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.bad_input import tiny_run  # noqa: F401 (fixture)
from tests.bad_input_os import fill, leftovers, nnik, one_error, small_tmpfs, snapshot, torn_files
from tests.files.test_pick_state import L_PATH
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)

# command -> (which run it needs, argv given (run, its scenario, a scratch dir)); the slow ones
# (run, select, search) only under the small limit, where they fail at their first large write
COMMANDS = {
    "run": ("tiny", lambda r, s, t: ["run", s, "-o", r]),
    "generate": ("tiny", lambda r, s, t: ["generate", s, "-o", r]),
    "train": ("tiny", lambda r, s, t: ["train", s, "-o", r]),
    "evaluate": ("tiny", lambda r, s, t: ["evaluate", r]),
    "export": ("tiny", lambda r, s, t: ["export", r]),
    "estimate": ("tiny", lambda r, s, t: ["estimate", r, "--target", "avr"]),
    "report": ("tiny", lambda r, s, t: ["report", r]),
    "tanh": ("tiny", lambda r, s, t: ["tanh"]),
    "synth-csv": ("tiny", lambda r, s, t: ["synth-csv", s, "-o", r / "marks.csv", "-n", 3000]),
    "select": ("picked", lambda r, s, t: ["select", r, "--family", "lut"]),
    "verify": ("picked", lambda r, s, t: ["verify", r, "--target", "avr"]),
    "search": ("picked", lambda r, s, t: ["search", r, "--trials", 2, "--families", "lut", "--no-warm-start"]),
    "job": ("picked", lambda r, s, t: ["job", r, L_PATH, "--no-chip"]),
    "export --arduino": ("picked", lambda r, s, t: ["export", r, "--arduino", r / "lib"]),
}
SLOW = ("run", "select", "search")
LIMITS = (2048, 40_000)  # bytes: below every real file (a tiny model.pt is 4 KB), and between the small files and the large ones


def _setup(kind: str, tiny_run, request, dest: Path) -> tuple[Path, Path]:
    if kind == "tiny":
        shutil.copytree(tiny_run, dest)
        return dest, tiny_run.parent / "tiny.toml"
    picked = request.getfixturevalue("picked_run")
    copy_picked(picked, dest)
    return dest, picked.parent / "tiny.toml"


def check_after(proc, run: Path, before: dict) -> str:
    if proc.returncode == 0:
        outcome = "fit"
    else:
        one_error(proc)
        outcome = "refused"
    assert leftovers(run) == [], leftovers(run)
    assert torn_files(run, before) == []
    return outcome


@pytest.mark.parametrize("limit", LIMITS)
@pytest.mark.parametrize("command", list(COMMANDS))
def test_file_size_limit(tiny_run, request, tmp_path, command, limit):  # noqa: F811
    if command in SLOW and limit != LIMITS[0]:
        pytest.skip("the small limit covers it (it fails at its first large write)")
    kind, argv = COMMANDS[command]
    run, toml = _setup(kind, tiny_run, request, tmp_path / "run")
    before = snapshot(run)
    proc = nnik(argv(run, toml, tmp_path), fsize=limit, cwd=tmp_path)
    outcome = check_after(proc, run, before)
    if limit == LIMITS[0] and command not in ("estimate", "tanh"):
        assert outcome == "refused", proc.stdout[-500:]  # every other command writes a file larger than 2 KB


@pytest.mark.parametrize("command", ["generate", "report", "job", "verify", "synth-csv", "export --arduino"])
def test_full_tmpfs(tiny_run, request, tmp_path, command):  # noqa: F811
    kind, argv = COMMANDS[command]
    with small_tmpfs(8192) as mnt:
        run, toml = _setup(kind, tiny_run, request, mnt / "run")
        fill(mnt, 24_000)
        before = snapshot(run)
        proc = nnik(argv(run, toml, tmp_path), cwd=tmp_path, env={"TMPDIR": str(mnt)})
        assert proc.returncode == 2, proc.stdout[-800:] + proc.stderr[-800:]
        one_error(proc)
        assert leftovers(run) == [] and torn_files(run, before) == []
        # room again: the same command now succeeds in the same directory
        (mnt / ".filler").unlink()
        proc = nnik(argv(run, toml, tmp_path), cwd=tmp_path, env={"TMPDIR": str(mnt)})
        assert proc.returncode == 0, proc.stderr[-2000:]
