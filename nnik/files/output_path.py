"""Output paths checked before a command does any work: never one of the command's inputs, never
a directory where a file goes (or a file where a directory goes), never under a file, and a
directory that nnik replaces as a whole only when nnik wrote it. Each refusal is one line."""

from __future__ import annotations

import ctypes
import os
import shutil
import tempfile
from pathlib import Path

from nnik.errors import NnikError


def nearest_existing(path: Path) -> Path:
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def same_file(a: Path, b: Path) -> bool:
    """One file under two names (a link, a relative path, the same path)?"""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(a).absolute().resolve() == Path(b).absolute().resolve()


def parent_ok(path: Path, what: str) -> None:
    """The nearest existing folder above path is a writable folder (not a file)."""
    base = nearest_existing(path.parent)
    if not base.is_dir():
        raise NnikError(f"{base} is a file, so it cannot hold {what}", str(path))
    if not os.access(base, os.W_OK | os.X_OK):
        raise NnikError(f"{base} is not writable", str(path))


def check_output_file(path: Path, inputs=(), what: str = "the output file") -> Path:
    """A file this command may write (replacing it atomically if it exists)."""
    path = Path(path)
    if not str(path).strip():
        raise NnikError(f"an empty name for {what}")
    if path.is_dir():
        raise NnikError(f"is a directory; {what} needs a file name", str(path))
    for inp in inputs:
        if inp is not None and path.exists() and same_file(path, inp):
            raise NnikError(f"is an input of this command ({inp}); nnik never writes over its inputs, choose "
                            "another file", str(path))
    parent_ok(path, what)
    return path


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> bool:
    """Swap two directory entries in one step (Linux renameat2); False where it is not offered."""
    try:
        fn = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):
        return False
    rc = fn(_AT_FDCWD, os.fsencode(str(a)), _AT_FDCWD, os.fsencode(str(b)), _RENAME_EXCHANGE)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: the file system cannot exchange
        return False
    raise OSError(err, os.strerror(err), str(b))


def replace_dir(staged: Path, dest: Path) -> None:
    """Put the directory ``staged`` in the place of ``dest``: where the kernel can, both entries
    are exchanged in one step (a kill leaves the old directory or the new one, whole); elsewhere
    the old one is renamed aside first. The old content is then removed."""
    from nnik.files.atomic_write import fsync_dir

    staged, dest = Path(staged), Path(dest)
    if not dest.exists():
        os.rename(staged, dest)
    elif _exchange(staged, dest):
        shutil.rmtree(staged, ignore_errors=True)  # now the old directory
    else:
        old = Path(tempfile.mkdtemp(prefix=f".{dest.name}.old-", dir=dest.parent))
        os.rename(dest, old / dest.name)
        os.rename(staged, dest)
        shutil.rmtree(old, ignore_errors=True)
    fsync_dir(dest.parent)
