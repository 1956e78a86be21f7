"""The one jinja2 environment every C generator renders with (templates live in codegen/)."""

from __future__ import annotations

import shutil
from functools import lru_cache
from pathlib import Path

import jinja2

CODEGEN = Path(__file__).resolve().parents[2] / "codegen"
TEMPLATES = CODEGEN / "templates"
RUNTIME = CODEGEN / "runtime"
RUNTIME_HEADERS = ("nnik_flash.h", "nnik_kernel.h")  # copied next to every generated file


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )


def write_sources(files: dict[str, str], outdir: Path) -> list[Path]:
    """Write generated files plus the runtime headers they include; returns the paths."""
    outdir.mkdir(parents=True, exist_ok=True)
    paths = []
    for fname, text in files.items():
        p = outdir / fname
        p.write_text(text)
        paths.append(p)
    for header in RUNTIME_HEADERS:
        shutil.copy(RUNTIME / header, outdir / header)
    return paths
