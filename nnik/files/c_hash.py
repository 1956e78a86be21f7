"""The identity of emitted C: a hash over a model's NAME.c and NAME.h. Every stored verification
result carries the hash of the files it ran; the report shows a result only while the files in
OUTDIR still hash the same."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Mapping


def files_hash(files: Mapping[str, str | bytes]) -> str:
    h = hashlib.sha256()
    for name in sorted(files):
        text = files[name]
        h.update(name.encode() + b"\0" + (text if isinstance(text, bytes) else text.encode()) + b"\0")
    return h.hexdigest()[:16]


def dir_hash(c_dir: Path, name: str) -> str | None:
    """Hash of c_dir/NAME.c and c_dir/NAME.h as they are on disk (None if either is missing)."""
    files = {}
    for suffix in (".c", ".h"):
        p = Path(c_dir) / f"{name}{suffix}"
        if not p.is_file():
            return None
        files[p.name] = p.read_bytes()
    return files_hash(files)
