"""An operating-system refusal (a full disk, a file too large for the limit, a read-only or
unwritable place, a path through a file) becomes the one line a user sees, never a traceback.
Every output nnik trusts is written atomically (nnik.files.atomic_write), so a command that
stops here leaves each such file as it was or whole."""

from __future__ import annotations

import errno

HINTS = {
    errno.ENOSPC: "the disk is full; free some space and run the command again",
    errno.EDQUOT: "the disk quota is used up; free some space and run the command again",
    errno.EFBIG: "the file would exceed the file-size limit (ulimit -f); raise it and run the command again",
    errno.EROFS: "the file system is read-only; choose a writable place",
    errno.EACCES: "permission denied; choose a writable place",
    errno.EPERM: "operation not permitted; choose a writable place",
}


def behind(exc: BaseException | None, kind: type[BaseException]) -> BaseException | None:
    """The first exception of ``kind`` in exc's chain (exc itself, then what it was raised from or
    while handling): a library's own error can hide the one that matters."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, kind):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def os_error_behind(exc: BaseException) -> OSError | None:
    """The OSError a library's own error was raised while handling (optuna's storage, for one,
    ends a trial whose journal write failed with an AssertionError of its own)."""
    return behind(exc, OSError)


def os_error_line(exc: OSError) -> str:
    """``PATH: what went wrong [ERRNO]; what to do`` for the one `nnik: error:` line."""
    name = errno.errorcode.get(exc.errno, "") if exc.errno is not None else ""
    what = exc.strerror or str(exc)
    hint = HINTS.get(exc.errno)
    where = exc.filename if exc.filename is not None else None
    text = f"{what}{f' [{name}]' if name else ''}"
    if hint:
        text += f": {hint}"
    return f"{where}: {text}" if where else text
