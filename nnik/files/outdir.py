"""Output and model directories checked before any stage runs: one line, never an OSError later."""

from __future__ import annotations

import fcntl
import os
import time
from pathlib import Path

from nnik.errors import NnikError
from nnik.files.output_path import nearest_existing

JOB_DIR = "job"  # OUTDIR/job/: what `nnik job` leaves (the report embeds it)


LOCK_FILE = ".nnik.lock"
_HELD: dict[str, int] = {}  # resolved directory -> descriptor holding its lock until the process ends


def hold_lock(path: Path) -> None:
    """Take OUTDIR/.nnik.lock for the rest of this process (flock: the kernel drops it when the
    process ends, however it ends). A second nnik writing into the same directory gets one line."""
    key = str(Path(path).resolve())
    if key in _HELD:
        return
    lock = Path(path) / LOCK_FILE
    while True:
        fd = _locked(lock, path)
        try:  # the holder before us may have removed the file as it ended: then lock the new one
            if os.fstat(fd).st_ino == os.stat(lock).st_ino:
                break
        except FileNotFoundError:
            pass
        os.close(fd)
    os.ftruncate(fd, 0)
    os.pwrite(fd, str(os.getpid()).encode(), 0)
    _HELD[key] = fd


def _holder_pid(fd: int) -> str:
    """The pid the holder wrote (it writes it just after it locks: a short wait for it)."""
    for _ in range(20):
        other = os.pread(fd, 32, 0).decode(errors="replace").strip()
        if other:
            return other
        time.sleep(0.05)
    return ""


def _locked(lock: Path, path: Path) -> int:
    try:
        fd = os.open(lock, os.O_CREAT | os.O_RDWR, 0o644)
    except OSError as exc:
        raise NnikError(f"cannot create the lock file ({exc.strerror or exc})", str(lock)) from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        try:
            other = _holder_pid(fd)
        finally:
            os.close(fd)
        raise NnikError(f"another nnik command{' (pid ' + other + ')' if other else ''} is writing into this "
                        "directory; wait for it to finish or choose another -o", str(path)) from None
    return fd


def release_locks() -> None:
    """Drop every lock this process holds and remove the lock files (the end of a command)."""
    for key, fd in list(_HELD.items()):
        try:
            (Path(key) / LOCK_FILE).unlink(missing_ok=True)
        except OSError:
            pass
        os.close(fd)
        del _HELD[key]


def check_outdir(path: Path, create: bool = False) -> Path:
    """A directory nnik may write into: not a file, not under a file, writable. With create, it is
    made now (so a read-only or impossible place fails here, before any work)."""
    path = Path(path)
    src = str(path)
    if path.exists() and not path.is_dir():
        raise NnikError("exists and is not a directory; choose another output directory", src)
    base = nearest_existing(path)
    if not base.is_dir():
        raise NnikError(f"{base} is a file, so it cannot hold an output directory", src)
    if not os.access(base, os.W_OK | os.X_OK):
        raise NnikError(f"{base} is not writable", src)
    if create and not path.is_dir():
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise NnikError(f"cannot create the output directory ({exc.strerror or exc})", src) from None
    if path.is_dir():
        hold_lock(path)
    return path


def check_model_dir(path: Path, *subdirs: str) -> Path:
    """An existing directory of a previous run; `subdirs` (e.g. "c") must be directories if present."""
    path = Path(path)
    if not path.exists():
        raise NnikError("no such directory (run `nnik run` or `nnik generate` first)", str(path))
    if not path.is_dir():
        raise NnikError("is a file, not an nnik output directory", str(path))
    for sub in subdirs:
        p = path / sub
        if p.exists() and not p.is_dir():
            raise NnikError(f"is a file where nnik writes the directory {sub}/; move it away", str(p))
    return check_outdir(path)
