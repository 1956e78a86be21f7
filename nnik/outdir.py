"""Output and model directories checked before any stage runs: one line, never an OSError later."""

from __future__ import annotations

import os
from pathlib import Path

from nnik.errors import NnikError


def _nearest_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def check_outdir(path: Path, create: bool = False) -> Path:
    """A directory nnik may write into: not a file, not under a file, writable. With create, it is
    made now (so a read-only or impossible place fails here, before any work)."""
    path = Path(path)
    src = str(path)
    if path.exists() and not path.is_dir():
        raise NnikError("exists and is not a directory; choose another output directory", src)
    base = _nearest_existing(path)
    if not base.is_dir():
        raise NnikError(f"{base} is a file, so it cannot hold an output directory", src)
    if not os.access(base, os.W_OK | os.X_OK):
        raise NnikError(f"{base} is not writable", src)
    if create and not path.is_dir():
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise NnikError(f"cannot create the output directory ({exc.strerror or exc})", src) from None
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
