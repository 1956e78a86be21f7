"""grbl 1.1's error numbers (doc/markdown/error_codes.md), and nnik's own after grbl's last (38).

The chip answers ``error:N``; the host model gives the same number and names the detail
(``error:20 unsupported command: G81 (a canned cycle)``). nnik_gcode.h holds the same numbers.
"""

from __future__ import annotations

TEXT = {
    1: "expected command letter",
    2: "bad number format",
    3: "invalid $ statement",
    4: "negative value",
    9: "G-code locked out during alarm",
    11: "line overflow: more than 79 characters after comments and blanks",
    20: "unsupported command",
    22: "undefined feed rate",
    23: "command value not integer",
    24: "axis command conflict",
    25: "word repeated",
    26: "no axis words",
    27: "invalid line number",
    28: "value word missing",
    29: "unsupported coordinate system",
    30: "G53 needs G0 or G1",
    31: "axis words with no command that uses them",
    32: "arc without an in-plane axis word",
    33: "invalid target",
    34: "arc radius error",
    35: "arc without an in-plane offset word",
    36: "unused words",
    37: "G43.1 needs Z",
    38: "tool number greater than 255",
    # nnik's own, after grbl's last code
    39: "bad checksum",
    40: "checksum mismatch",
    41: "named parameters and expressions are not supported",
    42: "O-word subroutines and program flow are not supported",
    43: "probing is not supported: this machine has no probe",
}

ALARM_TEXT = {2: "target beyond the travel (soft limit)"}
NNIK_FIRST = 39


class GcodeLineError(ValueError):
    """One refused line: grbl's error number and what exactly is wrong."""

    def __init__(self, code: int, detail: str = ""):
        self.code, self.detail = code, detail
        super().__init__(describe(code, detail))


class GcodeAlarm(GcodeLineError):
    """ALARM:n: the machine stops (2: a target beyond the travel)."""


def describe(code: int, detail: str = "") -> str:
    text = f"error:{code} {TEXT.get(code, 'error')}"
    return f"{text}: {detail}" if detail else text
