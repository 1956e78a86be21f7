"""Generated files land all at once or not at all: a stage collects its files, and only when it
has everything does :meth:`Staged.commit` write them to a temporary folder beside the output
and move each into place (``os.replace``, atomic per file). A stage that fails before the
commit leaves the output directory exactly as it was."""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import sys
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def held_interrupt():
    """Ctrl-C (SIGINT) held back while the block runs and delivered when it ends: a rename
    sequence or a clean-up is never cut in half (the main thread only: Python raises
    KeyboardInterrupt nowhere else)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextmanager
def temporary_folder(parent: Path, prefix: str, mode: int = 0o777):
    """A new empty folder parent/prefixXXXXXXXX (mode as mkdir takes it: the umask applies), removed
    however the block ends. A Ctrl-C cannot leave it behind: its name is held before the mkdir (an
    interrupt that Python raises just after the mkdir still finds it; tempfile.mkdtemp could be cut
    between its mkdir and its return), and the removal starts again if an interrupt cuts it, the
    interrupt raised once the folder is gone."""
    parent = Path(parent)
    parent.mkdir(parents=True, exist_ok=True)
    path = None
    try:
        for _ in range(100):
            name = parent / f"{prefix}{secrets.token_hex(4)}"
            if not name.exists():
                path = name
                os.mkdir(path, mode)
                break
        else:
            raise FileExistsError(f"no free name {prefix}* in {parent}")
        yield path
    finally:
        interrupted = False
        while True:
            try:
                if path is not None:
                    shutil.rmtree(path, ignore_errors=True)
                break
            except KeyboardInterrupt:
                interrupted = True
        if interrupted:
            raise KeyboardInterrupt


def reraise_lost_interrupts() -> None:
    """A Ctrl-C that lands in a finaliser or a weakref callback (matplotlib has many) is
    'ignored' by Python with a traceback on stderr, and the command would run on: raise it
    again instead, where it can stop the command."""
    default = sys.unraisablehook
    if getattr(default, "nnik", False):
        return

    def hook(u):
        if isinstance(u.exc_value, KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)
            return
        default(u)

    hook.nnik = True
    sys.unraisablehook = hook


def write_file_atomic(path: Path, data: str | bytes) -> None:
    """Replace one file in a single step: a temporary file beside it, flushed to disk, then
    ``os.replace`` (and the directory flushed), so a crash leaves the old file or the new one,
    never half of either."""
    with replacing(path) as tmp:
        tmp.write_bytes(data.encode() if isinstance(data, str) else data)


@contextmanager
def replacing(path: Path):
    """For writers that take a file name (numpy, torch, onnx, matplotlib): yields a temporary
    name beside ``path`` with the same suffix; when the block ends without an error the file is
    flushed and moved onto ``path`` in one step, otherwise it is removed and ``path`` is as it was."""
    path = Path(path)
    tmp = None
    try:
        # the name is held before a Ctrl-C can be raised: one that lands while mkstemp makes the
        # file is raised after the with, inside this try, which removes the file
        with held_interrupt():
            fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}", dir=path.parent)
            os.close(fd)
        yield Path(tmp)
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        with held_interrupt():
            os.replace(tmp, path)
    except BaseException:
        if tmp is not None:
            with held_interrupt():
                Path(tmp).unlink(missing_ok=True)
        raise
    fsync_dir(path.parent)


def fsync_dir(d: Path) -> None:
    """Flush a directory entry change (a rename or an unlink) to disk."""
    try:
        fd = os.open(d, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class Staged:
    def __init__(self, root: Path):
        self.root = Path(root)
        self.files: dict[Path, bytes] = {}  # relative path -> content

    def add(self, files: dict[str, str], subdir: str | Path = ".", runtime_headers: bool = True) -> None:
        """Generated sources for root/subdir, plus the runtime headers they include."""
        from nnik.emit.templating import RUNTIME, RUNTIME_HEADERS

        d = Path(subdir)
        for name, text in files.items():
            self.files[d / name] = text.encode()
        if runtime_headers:
            for h in RUNTIME_HEADERS:
                self.files[d / h] = (RUNTIME / h).read_bytes()

    def commit(self) -> list[Path]:
        self.root.mkdir(parents=True, exist_ok=True)
        with temporary_folder(self.root, ".staging-", 0o700) as tmp:
            for rel, data in self.files.items():
                p = tmp / rel
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_bytes(data)
            out = []
            with held_interrupt():  # every file moved in, or (an error) none more
                for rel in self.files:
                    dest = self.root / rel
                    dest.parent.mkdir(parents=True, exist_ok=True)
                    os.replace(tmp / rel, dest)
                    out.append(dest)
            return out
