"""PIC18 (SDCC pic16) path of the `poly` family."""
from __future__ import annotations


def p18_body(impl) -> str | None:
    return None
