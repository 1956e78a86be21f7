"""A line's bytes as grbl's protocol layer reads them, byte by byte (nnik_gc_byte in C).

What a sender puts on the wire first: ``sendable`` drops grbl's realtime bytes (``?`` ``!`` ``~``
and Ctrl-X act at once on the chip, wherever they stand) and bytes >= 0x80 (grbl's extended
realtime commands; a UTF-8 comment or a byte-order mark). Then the reader, as grbl's
protocol.c: blanks and control characters dropped, ``/`` (block delete) dropped, ``(`` to the first
``)`` and ``;`` to the end are comments, lower case raised; 79 characters fit, more is error 11.
nnik's additions: a ``%`` line is a program delimiter (ignored whole), and ``*nn`` outside a
comment ends the line with Marlin's checksum, the XOR of every byte before the ``*``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

LINE_MAX = 79  # grbl's 80-byte line buffer
REALTIME = frozenset(b"?!~\x18")

EMPTY, DOLLAR, LINE, ERROR = "empty", "dollar", "line", "error"


def sendable(raw: bytes) -> bytes:
    """The bytes of a line that reach the reader: realtime characters and bytes >= 0x80 out."""
    return bytes(c for c in raw if c < 0x80 and c not in REALTIME)


@dataclass(frozen=True)
class ReadLine:
    kind: str  # EMPTY (blank, comment or %), DOLLAR ($ line), LINE (words), ERROR
    text: str = ""  # the cleaned line (upper case, no blanks or comments)
    code: int = 0  # grbl's error number for ERROR


def read_line(data: bytes) -> ReadLine:
    """One line's bytes (after ``sendable``, without its end) through the reader."""
    out: list[str] = []
    mode = 0  # 0 words, 1 '(' comment, 2 ';' comment, 3 checksum digits, 4 a '%' line, 5 after the checksum
    over = x = 0
    total = digits = 0
    blank_after = bad = False
    for c in data:
        if mode == 5:  # a comment after the checksum
            continue
        if mode == 3:
            if c == 59:  # ';': a comment after the checksum
                mode = 5
            elif 48 <= c <= 57 and not blank_after:
                total = total * 10 + c - 48
                digits += 1
                bad = bad or digits > 3
            elif c <= 32:
                blank_after = digits > 0
            else:
                bad = True
            continue
        if c == 42 and mode == 0:  # '*'
            mode = 3
            continue
        x ^= c
        if mode == 1:
            mode = 0 if c == 41 else 1
        elif mode in (2, 4):
            continue
        elif c <= 32 or c == 47:  # blanks, control characters, '/'
            continue
        elif c == 40:
            mode = 1
        elif c == 59:
            mode = 2
        elif c == 37 and not out:  # '%'
            mode = 4
        elif len(out) >= LINE_MAX:
            over = 1
        else:
            out.append(chr(c - 32) if 97 <= c <= 122 else chr(c))
    if mode in (3, 5):
        if bad or not digits or total > 255:
            return ReadLine(ERROR, code=39)
        if total != x:
            return ReadLine(ERROR, code=40)
    if over:
        return ReadLine(ERROR, code=11)
    if not out:
        return ReadLine(EMPTY)
    text = "".join(out)
    return ReadLine(DOLLAR if text[0] == "$" else LINE, text)


def split_lines(data: bytes) -> list[bytes]:
    """A file's lines: LF, CRLF (or CR CR LF, as some CAM posts write) or CR alone end a line; the
    last line needs no end."""
    lines = re.sub(rb"\r+\n", b"\n", data).replace(b"\r", b"\n").split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()
    return lines
