"""The one jinja2 environment every C generator renders with (templates live in codegen/)."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import jinja2

CODEGEN = Path(__file__).resolve().parents[2] / "codegen"
TEMPLATES = CODEGEN / "templates"
RUNTIME = CODEGEN / "runtime"


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
