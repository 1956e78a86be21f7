"""The command blocks of the README and docs/*.md, and a fresh copy of the repository to run them in.

A page marks what the tests run: every line of a ```sh block is a command, run verbatim from the
root of a fresh copy (comments and blank lines aside). ```console blocks show commands a user
types that the tests cannot run inside themselves (`make test`, installing toolchains), and
```text blocks show output. Any `nnik` command a page shows outside ```sh must also be in one of
its ```sh blocks, so that no shown command escapes the tests, unless the page shows it failing:
a `$ nnik ...` line followed by its `nnik: error: ...` line, which the tests run after the page's
```sh commands and hold to exit 2 and that very line."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from tests.conftest import ROOT

FENCE = re.compile(r"^```([\w-]*)\n(.*?)^```", re.S | re.M)
LANGUAGES = {"sh", "console", "text", "toml", "c", "csv"}


def pages() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def blocks(page: Path) -> list[tuple[str, str]]:
    """(language, body) of every fenced block of the page."""
    return FENCE.findall(page.read_text())


def _lines(body: str) -> list[str]:
    return [ln.strip() for ln in body.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]


def commands(page: Path) -> list[str]:
    """The page's ```sh lines, in order."""
    return [c for lang, body in blocks(page) if lang == "sh" for c in _lines(body)]


def _shown(page: Path) -> list[tuple[str, str | None]]:
    """(command, the error line after it or None) of each `nnik ...` line (after an optional "$ ")
    in the page's ```console and ```text blocks."""
    out = []
    for lang, body in blocks(page):
        if lang in ("console", "text"):
            lines = body.splitlines()
            for i, ln in enumerate(lines):
                if m := re.match(r"\s*\$?\s*(nnik \S.*)$", ln):
                    nxt = lines[i + 1].strip() if i + 1 < len(lines) else ""
                    out.append((m.group(1).strip(), nxt if nxt.startswith("nnik: error: ") else None))
    return out


def shown_nnik_commands(page: Path) -> list[str]:
    """The `nnik` commands a page shows outside ```sh, failures aside."""
    return [cmd for cmd, err in _shown(page) if err is None]


def shown_failures(page: Path) -> list[tuple[str, str]]:
    """(command, its one error line) that the page shows failing."""
    return [(cmd, err) for cmd, err in _shown(page) if err is not None]


def fresh_copy(dst: Path) -> Path:
    """The tracked files of the repository (what a clone has), without build/ or caches."""
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for rel in filter(None, files.decode().split("\0")):
        src = ROOT / rel
        if src.is_file():
            (dst / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst / rel)
    return dst
