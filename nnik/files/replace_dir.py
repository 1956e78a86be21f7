"""A generated folder (the Arduino library) replaced as a whole: written complete into a temporary
folder beside it, then swapped in, so no file of an earlier export stays behind and a crash leaves
the old folder or the new one.  The swap is one atomic renameat2(RENAME_EXCHANGE) on Linux, else
two renames.  A folder is replaced only when nnik wrote it (its marker file is in it) or it is
empty: a user's own folder is never wiped."""

from __future__ import annotations

import ctypes
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from nnik.errors import NnikError
from nnik.files.atomic_write import fsync_dir

AT_FDCWD, RENAME_EXCHANGE = -100, 2


def check_replaceable(dest: Path, marker: str, what: str) -> None:
    """NnikError unless dest is absent, empty, or a folder nnik wrote (marker inside)."""
    if not dest.exists() and not dest.is_symlink():
        return
    if dest.is_symlink() or not dest.is_dir():
        raise NnikError(f"exists and is not a folder; {what} writes a folder", str(dest))
    if (dest / marker).is_file() or not any(dest.iterdir()):
        return
    raise NnikError(f"exists and was not written by nnik (no {marker} in it): nnik replaces only a {what} it "
                    "wrote; give a new folder, or empty this one", str(dest))


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux renameat2); False where the system cannot."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return fn(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE) == 0


def swap_in(new: Path, dest: Path) -> None:
    """new (a complete folder beside dest) takes dest's place; dest's old content is removed."""
    if not dest.exists():
        os.rename(new, dest)
    elif _exchange(new, dest):
        shutil.rmtree(new)  # now the old folder
    else:
        old = new.with_name(new.name + ".old")
        os.rename(dest, old)
        try:
            os.rename(new, dest)
        except OSError:
            os.rename(old, dest)
            raise
        shutil.rmtree(old)
    fsync_dir(dest.parent)


@contextmanager
def staged_folder(dest: Path, marker: str, what: str, stamp: str):
    """Yield a temporary folder beside dest to fill; on success it becomes dest (with the marker,
    holding `stamp`); on failure dest is as it was."""
    dest = Path(dest)
    check_replaceable(dest, marker, what)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", suffix=".new", dir=dest.parent))
    try:
        yield tmp
        (tmp / marker).write_text(stamp)
        swap_in(tmp, dest)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
