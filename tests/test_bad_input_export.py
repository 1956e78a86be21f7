"""`nnik export --arduino DIR` into a folder that is already there (issue 25): an earlier export's
folder is replaced as a whole (none of its files left, so its examples never build with another
machine's config), and a folder nnik did not write is refused and left as it was."""

from __future__ import annotations

from nnik.cli import main
from nnik.firmware.arduino import MARKER
from tests.bad_input import fails, snapshot
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)


def test_reexport_replaces_the_earlier_library_whole(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    lib = tmp_path / "lib"
    assert main(["export", str(run), "--arduino", str(lib)]) == 0
    first = snapshot(lib)
    assert (lib / MARKER).is_file()
    # what an earlier export of another machine left: its examples, its IK, its config
    stale = [lib / "examples" / "other_selftest" / "other_selftest.ino", lib / "src" / "other.c",
             lib / "src" / "other.h"]
    for f in stale:
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text("/* an earlier machine's */\n")
    assert main(["export", str(run), "--arduino", str(lib)]) == 0
    assert not any(f.exists() for f in stale)
    assert snapshot(lib) == first  # the same library, byte for byte, and nothing else
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".lib.")]  # no staging folder left


def test_a_folder_nnik_did_not_write_is_refused_untouched(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    mine = tmp_path / "my_sketches"
    (mine / "blink").mkdir(parents=True)
    (mine / "blink" / "blink.ino").write_text("void setup() {}\nvoid loop() {}\n")
    fails(capsys, ["export", run, "--arduino", mine], str(mine), "not written by nnik", watch=mine)


def test_an_empty_folder_is_used(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["export", str(run), "--arduino", str(empty)]) == 0
    assert (empty / MARKER).is_file() and (empty / "library.properties").is_file()
