"""A read-only output for every command (issue 25, part 6): chmod a-w for an ordinary user
(EACCES), a read-only bind mount as root, whom modes do not stop (EROFS). A command that must
write there answers one `nnik: error:` line and exit 2; one that writes nothing there (tanh, and
any command whose outputs fit elsewhere) succeeds; the place is unchanged either way."""

from __future__ import annotations

import pytest

from tests.bad_input import tiny_run  # noqa: F401 (fixture)
from tests.bad_input_os import nnik, one_error, read_only, snapshot
from tests.pick_fixtures import picked_run  # noqa: F401 (fixture)
from tests.test_bad_input_disk import COMMANDS, _setup

WRITES_NOTHING = ("tanh",)


@pytest.mark.parametrize("command", list(COMMANDS))
def test_read_only_output(tiny_run, request, tmp_path, command):  # noqa: F811
    kind, argv = COMMANDS[command]
    run, toml = _setup(kind, tiny_run, request, tmp_path / "run")
    before = snapshot(run)
    with read_only(run):
        proc = nnik(argv(run, toml, tmp_path), cwd=run, timeout=900)
    if command in WRITES_NOTHING:
        assert proc.returncode == 0, proc.stderr[-2000:]
    else:
        line = one_error(proc)
        assert any(w in line for w in ("Read-only file system", "Permission denied", "not writable")), line
    assert snapshot(run) == before


def test_read_only_parent_of_a_new_outdir(tiny_run, tmp_path):  # noqa: F811
    parent = tmp_path / "ro"
    parent.mkdir()
    with read_only(parent):
        proc = nnik(["generate", tiny_run.parent / "tiny.toml", "-o", parent / "new" / "out"])
    one_error(proc, "not writable")
    assert list(parent.iterdir()) == []


def test_read_only_parent_of_the_csv(tiny_run, tmp_path):  # noqa: F811
    parent = tmp_path / "ro"
    parent.mkdir()
    with read_only(parent):
        proc = nnik(["synth-csv", tiny_run.parent / "tiny.toml", "-o", parent / "m.csv", "-n", 30])
    one_error(proc, "not writable")
    assert list(parent.iterdir()) == []
