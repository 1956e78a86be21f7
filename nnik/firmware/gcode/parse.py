"""G-code lines -> words, exactly as codegen/arduino/src/nnik_gcode.c reads them.

A small own parser rather than gcodeparser (PyPI): the firmware reads numbers as exact decimals
into whole micrometres (round half away from zero, e.g. 0.0025 in = 63.5 um -> 64 um), and the
Python model must make the same choice bit for bit; gcodeparser hands out floats. The error
texts are the firmware's, word for word, so a bad line reads the same on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass, field

LINE_MAX = 95  # characters per line, comments included (NNIK_GC_LINE_MAX)
INT_DIGITS_MAX = 9999
DECIMALS_MAX = 6
AXIS_LETTERS = "XYIJRFPSZ"
N_DIGITS_MAX = 8
ACCEPTED_MODES = (17, 40, 49, 54, 64, 80, 94)  # the only plane, compensation, system, path, feed mode


class GcodeLineError(ValueError):
    """One bad line; the message is the firmware's text (without 'error: line N: ')."""


@dataclass(frozen=True)
class Num:
    """A scanned decimal: [-]ip.fr with nd fraction digits (dot: a '.' was written)."""

    neg: bool
    dot: bool
    ip: int
    fr: int
    nd: int

    def to_um(self, inch: bool) -> int:
        """Whole micrometres (or um/min): ip * scale + round_half_up(fr * scale / 10^nd), signed."""
        scale = 25400 if inch else 1000
        p = 10**self.nd
        v = self.ip * scale + (self.fr * scale + p // 2) // p
        return -v if self.neg else v


@dataclass
class Words:
    """What one line says: axis words, the motion command and modal changes it carries."""

    values: dict[str, Num] = field(default_factory=dict)  # X Y I J R F P
    motion: int | None = None
    inch: bool | None = None
    relative: bool | None = None
    wait: bool = False
    end: bool = False  # M2/M30
    spindle: int | None = None  # M3, M4, M5
    nonmodal: int = 0  # 4, 28, 92


def checksum(rest: str, x: int) -> None:
    """The digits after '*' against x, the XOR of the bytes before it (Marlin)."""
    i = 0
    while i < len(rest) and "0" <= rest[i] <= "9":
        i += 1
        if i > 3:
            raise GcodeLineError("bad checksum")
    if not i or rest[i:].strip(" \t\r") or int(rest[:i]) > 255:
        raise GcodeLineError("bad checksum")
    if int(rest[:i]) != x:
        raise GcodeLineError("checksum mismatch")


def clean(line: str) -> str:
    """Drop blanks, '(...)' and ';...' comments; upper-case; '*nn' (outside comments) ends the
    line and must be the XOR of the bytes before it."""
    if len(line) > LINE_MAX:
        raise GcodeLineError("line too long")
    out, in_comment, x = [], False, 0
    for k, c in enumerate(line):
        if k:
            x ^= ord(line[k - 1])
        if in_comment:
            in_comment = c != ")"
            continue
        if c == ";":
            break
        if c == "*":
            checksum(line[k + 1:], x)
            break
        if c == "(":
            in_comment = True
            continue
        if c in " \t\r":
            continue
        out.append(c.upper() if "a" <= c <= "z" else c)
    if in_comment:
        raise GcodeLineError("unterminated comment")
    return "".join(out)


def scan_num(s: str, i: int, letter: str) -> tuple[Num, int]:
    neg = dot = False
    ip = fr = nd = digits = 0
    if i < len(s) and s[i] in "+-":
        neg = s[i] == "-"
        i += 1
    while i < len(s) and "0" <= s[i] <= "9":
        if ip > INT_DIGITS_MAX // 10:
            raise GcodeLineError(f"number too large after {letter}")
        ip = ip * 10 + int(s[i])
        i += 1
        digits += 1
    if i < len(s) and s[i] == ".":
        i += 1
        dot = True
        while i < len(s) and "0" <= s[i] <= "9":
            if nd == DECIMALS_MAX:
                raise GcodeLineError(f"too many decimals after {letter}")
            fr = fr * 10 + int(s[i])
            nd += 1
            i += 1
            digits += 1
    if not digits:
        raise GcodeLineError(f"bad number after {letter}")
    return Num(neg, dot, ip, fr, nd), i


def parse_line(line: str, pen: bool = False) -> Words:
    """Words of one line (without its newline); GcodeLineError names what is wrong. Z is a word
    only on pen machines (MachineConfig.tool "pen" or "servo")."""
    s = clean(line)
    w = Words()
    if s == "%":  # a program's first or last line, as CAM posts write it
        return w
    i = 0
    while i < len(s):
        letter = s[i]
        i += 1
        if not "A" <= letter <= "Z":
            raise GcodeLineError("unexpected character")
        if letter not in AXIS_LETTERS + "NGM" or (letter == "Z" and not pen):
            raise GcodeLineError(f"unsupported word {letter}")
        if letter == "N":  # a line number: up to 8 digits, read and ignored
            k = i
            while i < len(s) and "0" <= s[i] <= "9":
                i += 1
                if i - k > N_DIGITS_MAX:
                    raise GcodeLineError("number too large after N")
            if i == k:
                raise GcodeLineError("bad number after N")
            continue
        n, i = scan_num(s, i, letter)
        if letter in AXIS_LETTERS:
            if letter in w.values:
                raise GcodeLineError(f"repeated word {letter}")
            w.values[letter] = n
            continue
        if letter == "G" and n.dot and not n.neg and n.nd == 1:
            raise GcodeLineError(f"unsupported G{n.ip}.{n.fr}")
        if n.neg or n.dot:
            raise GcodeLineError(f"{letter} needs a whole number")
        if letter == "G":
            if n.ip <= 3:
                if w.motion is not None:
                    raise GcodeLineError("two motion commands")
                w.motion = n.ip
            elif n.ip in (20, 21):
                w.inch = n.ip == 20
            elif n.ip in (4, 28, 92):
                if w.nonmodal:
                    raise GcodeLineError("two non-modal commands")
                w.nonmodal = n.ip
            elif n.ip in (90, 91):
                w.relative = n.ip == 91
            elif n.ip not in ACCEPTED_MODES:
                raise GcodeLineError(f"unsupported G{n.ip}")
        elif n.ip in (2, 30, 400):
            w.wait = True
            w.end = w.end or n.ip != 400
        elif n.ip <= 1:
            raise GcodeLineError(f"M{n.ip} pause not supported")
        elif 3 <= n.ip <= 5:
            if w.spindle is not None:
                raise GcodeLineError("two tool commands")
            w.spindle = n.ip
        else:
            raise GcodeLineError(f"unsupported M{n.ip}")
    return w


def split_lines(data: bytes) -> list[str]:
    """A job file's lines as the firmware receives them (bytes as latin-1, no newline)."""
    text = data.decode("latin-1")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines
