"""A generated folder (the Arduino library) replaced as a whole: written complete into a temporary
folder beside it, then swapped in, so no file of an earlier export stays behind and a crash leaves
the old folder or the new one.  The swap is one atomic renameat2(RENAME_EXCHANGE) on Linux, else
two renames.  A folder is replaced only when nnik wrote it (its marker file is in it) or it is
empty: a user's own folder is never wiped."""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

from nnik.errors import NnikError
from nnik.files.atomic_write import temporary_folder
from nnik.files.output_path import parent_ok, replace_dir


def check_replaceable(dest: Path, marker: str, what: str) -> None:
    """NnikError unless dest is absent, empty, or a folder nnik wrote (marker inside)."""
    if not dest.exists() and not dest.is_symlink():
        return parent_ok(dest, what)
    if dest.is_symlink() or not dest.is_dir():
        raise NnikError(f"exists and is not a folder; {what} writes a folder", str(dest))
    if (dest / marker).is_file() or not any(dest.iterdir()):
        return parent_ok(dest, what)
    raise NnikError(f"exists and was not written by nnik (no {marker} in it): nnik replaces only a {what} it "
                    "wrote; give a new folder, or empty this one", str(dest))


@contextmanager
def staged_folder(dest: Path, marker: str, what: str, stamp: str):
    """Yield a temporary folder beside dest to fill; on success it becomes dest (with the marker,
    holding `stamp`); on failure dest is as it was."""
    dest = Path(dest)
    check_replaceable(dest, marker, what)
    with temporary_folder(dest.parent, f".{dest.name}.staging-") as tmp:
        yield tmp
        (tmp / marker).write_text(stamp)
        replace_dir(tmp, dest)
