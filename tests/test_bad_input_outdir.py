"""`-o` paths that cannot hold an output directory (issue 11, section 3): one line and exit 2
before any stage runs, nothing written."""

from __future__ import annotations

import pytest

from tests.bad_input import GALVO, fails, with_training
from tests.conftest import write_toml


@pytest.fixture
def scenario(tmp_path):
    return write_toml(tmp_path, with_training(GALVO))


@pytest.mark.parametrize("command", ["generate", "run", "train"])
def test_outdir_is_an_existing_file(tmp_path, capsys, scenario, command):
    f = tmp_path / "taken"
    f.write_text("keep me\n")
    fails(capsys, [command, scenario, "-o", f], str(f), "exists and is not a directory", watch=tmp_path)
    assert f.read_text() == "keep me\n"


@pytest.mark.parametrize("command", ["generate", "run"])
def test_outdir_under_a_file(tmp_path, capsys, scenario, command):
    f = tmp_path / "afile"
    f.write_text("x")
    fails(capsys, [command, scenario, "-o", f / "sub" / "out"], f"{f} is a file", watch=tmp_path)


def test_outdir_cannot_be_created(tmp_path, capsys, scenario):
    """/proc refuses new directories even to root: the place is unwritable."""
    fails(capsys, ["generate", scenario, "-o", "/proc/nnik-cannot-exist/out"], "cannot create the output directory",
          watch=tmp_path)
