"""A measured log's text, read and checked before any parsing: a file, not over max_bytes, no NUL
byte, UTF-8 (a BOM dropped); its non-blank lines numbered, whatever their ends (LF, CRLF, CR).
Each problem raises `error` (the caller's one-line error type) naming it, with `what` the format."""

from __future__ import annotations

from pathlib import Path


def numbered_lines(path: Path, what: str, max_bytes: int, error=ValueError) -> list[tuple[int, str]]:
    path = Path(path)
    if not path.is_file():
        raise error("file not found" if not path.exists() else "not a file")
    size = path.stat().st_size
    if size > max_bytes:
        raise error(f"{size} bytes: larger than any {what} ({max_bytes >> 20} MiB)")
    data = path.read_bytes()
    if b"\0" in data:
        raise error(f"a binary file, not {what}")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise error(f"not text (not UTF-8): a binary file, not {what}") from None
    lines = [(i + 1, ln.strip()) for i, ln in enumerate(text.splitlines()) if ln.strip()]
    if not lines:
        raise error(f"empty file: expected {what}")
    return lines
