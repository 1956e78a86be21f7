"""nnik.files.replace_dir: a folder swapped in whole, an earlier one's files gone, a failure
leaving the old folder as it was, a folder without the marker refused."""

from __future__ import annotations

import pytest

from nnik.errors import NnikError
from nnik.files.replace_dir import staged_folder
from tests.bad_input import snapshot

M = ".marker"


def _fill(d, files):
    for rel, text in files.items():
        (d / rel).parent.mkdir(parents=True, exist_ok=True)
        (d / rel).write_text(text)


def test_replace_leaves_only_the_new_files(tmp_path):
    dest = tmp_path / "lib"
    with staged_folder(dest, M, "library", "1") as d:
        _fill(d, {"a.txt": "old", "sub/old.txt": "old"})
    with staged_folder(dest, M, "library", "2") as d:
        _fill(d, {"a.txt": "new"})
    assert sorted(p.name for p in dest.rglob("*")) == [M, "a.txt"]
    assert (dest / "a.txt").read_text() == "new" and (dest / M).read_text() == "2"
    assert [p.name for p in tmp_path.iterdir()] == ["lib"]


def test_a_failure_while_writing_leaves_the_old_folder(tmp_path):
    dest = tmp_path / "lib"
    with staged_folder(dest, M, "library", "1") as d:
        _fill(d, {"a.txt": "old"})
    before = snapshot(dest)
    with pytest.raises(RuntimeError):
        with staged_folder(dest, M, "library", "2") as d:
            _fill(d, {"a.txt": "half"})
            raise RuntimeError("disk full")
    assert snapshot(dest) == before and [p.name for p in tmp_path.iterdir()] == ["lib"]


def test_a_users_folder_and_a_file_are_refused(tmp_path):
    mine = tmp_path / "mine"
    _fill(mine, {"notes.txt": "keep"})
    with pytest.raises(NnikError, match="not written by nnik"):
        with staged_folder(mine, M, "library", "1"):
            pass
    assert (mine / "notes.txt").read_text() == "keep"
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(NnikError, match="not a folder"):
        with staged_folder(f, M, "library", "1"):
            pass
