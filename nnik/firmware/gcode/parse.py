"""A cleaned line (reader.read_line) -> its words, as nnik_gc_parse.c reads them.

Numbers are exact decimals, never floats: the firmware reads them into whole micrometres (round
half away from zero, e.g. 0.0025 in = 63.5 um -> 64 um) and the Python model must make the same
choice bit for bit. Up to 9 integer digits; decimals past the sixth are dropped.

Commands are kept as code10 = number x 10 + its first decimal (G28.1 -> 281, M862.3 -> 8623).
Within one modal group the last word wins (a Fanuc safety block ``G0 G90 G40 G21 G17 G94 G80``
reads as a Fanuc control reads it); the block counts how often that happened.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from nnik.firmware.config import FEATURES
from nnik.firmware.gcode.codes import GcodeLineError

INT_DIGITS_MAX = 9
DECIMALS_MAX = 6
VALUE_LETTERS = "EFHIJKLPQRSTXYZ"
EXTRA_AXES = "ABCUVW"
LINE_NUMBER_MAX = 10_000_000
SATURATE = 1 << 28

# G codes (code10) by modal group; group 0 is grbl's non-modal group
MOTION = {0: 0, 10: 1, 20: 2, 30: 3, 50: 5, 800: 80}
NONMODAL = {40: 4, 100: 10, 280: 28, 281: 281, 300: 30, 301: 301, 530: 53, 920: 92, 921: 921}
PLANE = {170: 0, 180: 1, 190: 2}
UNITS = {200: 1, 210: 0}
DISTANCE = {900: 0, 910: 1}
ARC_DISTANCE = {901: 1, 911: 0}
FEED_MODE = {930: 1, 940: 0}
TLO = {431: 1, 490: 0, 430: 2}  # G43.1 dynamic, G49 cancel, G43 H: a tool table (noted, offset 0)
WCS = {540: 0, 550: 1, 560: 2, 570: 3, 580: 4, 590: 5}
G_QUIET = {400, 610}  # grbl's own: cutter compensation off, exact path (nothing to do)
G_NOTED_WORD = {611: "G61.1", 640: "G64", 980: "G98", 990: "G99", 690: "G69", 970: "G97", 150: "G15"}
G_NOTED_LINE = {290: "G29"}  # bed levelling and such: the whole line is noted, whatever its words
G_MARLIN_NOTED_LINE = {100: "G10", 110: "G11", 120: "G12", 260: "G26", 270: "G27", 290: "G29", 330: "G33",
                       340: "G34", 350: "G35", 420: "G42", 760: "G76", 4250: "G425"}
PROBING = {310, 382, 383, 384, 385}
CANNED = {730, 760, 810, 820, 830, 840, 850, 860, 870, 880, 890}
# M codes
M_STOP = {0: 0, 10: 1, 20: 2, 300: 30}
M_SPINDLE = {30: 3, 40: 4, 50: 5}
M_COOLANT = {70: 7, 80: 8, 90: 9}
M_FLOW = {970, 980, 990}  # subprogram call and return


@dataclass(frozen=True)
class Num:
    """A scanned decimal: [-]ip.fr with nd fraction digits."""

    neg: bool
    ip: int
    fr: int
    nd: int

    def to_um(self, inch: bool = False) -> int:
        """Whole micrometres (or thousandths): ip * scale + round_half_up(fr * scale / 10^nd),
        saturated at 2^28 (beyond any coordinate: error 33 later)."""
        scale = 25400 if inch else 1000
        p = 10**self.nd
        v = min(self.ip * scale + (self.fr * scale + p // 2) // p, SATURATE)
        return -v if self.neg else v

    @property
    def code10(self) -> int:
        return self.ip * 10 + (self.fr // 10 ** (self.nd - 1) if self.nd else 0)


@dataclass
class Block:
    """What one line says. None: the line does not set that group."""

    values: dict[str, Num] = field(default_factory=dict)
    motion: int | None = None  # 0 1 2 3 5, 80 (none)
    nonmodal: int | None = None  # 4 10 28 281 30 301 53 92 921
    plane: int | None = None
    inch: int | None = None
    relative: int | None = None
    arc_abs: int | None = None
    inverse_time: int | None = None
    tlo: int | None = None
    wcs: int | None = None
    stop: int | None = None  # M0 M1 M2 M30
    spindle: int | None = None  # 3 4 5
    coolant: int | None = None  # 7 8 9
    m6: bool = False
    wait: bool = False  # M400
    e_relative: int | None = None  # M83 1, M82 0
    m300: bool = False
    noted_line: str | None = None  # the whole line is noted (a printer or machine setup code)
    noted: list[str] = field(default_factory=list)  # codes noted on a line that runs
    last_wins: int = 0  # words that replaced an earlier word of their modal group
    used: set = field(default_factory=set)  # the build options (FEATURE_CODES) its words need


def scan_num(s: str, i: int) -> tuple[Num, int]:
    """[+-]digits[.digits] at s[i:]; error 2 if there is none."""
    neg = False
    ip = fr = nd = digits = 0
    if i < len(s) and s[i] in "+-":
        neg = s[i] == "-"
        i += 1
    while i < len(s) and "0" <= s[i] <= "9":
        if digits == INT_DIGITS_MAX:
            raise GcodeLineError(2, "more than 9 integer digits")
        ip = ip * 10 + ord(s[i]) - 48
        i += 1
        digits += 1
    if i < len(s) and s[i] == ".":
        i += 1
        while i < len(s) and "0" <= s[i] <= "9":
            if nd < DECIMALS_MAX:
                fr = fr * 10 + ord(s[i]) - 48
                nd += 1
            i += 1
            digits += 1
    if not digits:
        if i < len(s) and s[i] in "#[":
            raise GcodeLineError(41, s[i])
        raise GcodeLineError(2)
    return Num(neg, ip, fr, nd), i


def _set(b: Block, name: str, value) -> None:
    if getattr(b, name) is not None:
        b.last_wins += 1
    setattr(b, name, value)


FEATURE_CODES = {"g5": {50}, "g93": {930}, "planes": {180, 190}, "wcs": {100, 281, 301, 550, 560, 570, 580, 590}}
assert set(FEATURE_CODES) == FEATURES


def _g(b: Block, n: Num, marlin: bool, features=FEATURES) -> None:
    c = n.code10
    name = f"G{n.ip}" + (f".{c % 10}" if c % 10 else "")
    if n.neg:
        raise GcodeLineError(20, name)
    if n.nd > 1 and n.fr % 10 ** (n.nd - 1):
        raise GcodeLineError(23, f"G{n.ip}.{n.fr}")
    noted_line = G_MARLIN_NOTED_LINE if marlin else G_NOTED_LINE
    off = next((f for f, codes in FEATURE_CODES.items() if c in codes and f not in features), None)
    if off and c not in noted_line:
        raise GcodeLineError(20, f"{name}: this build leaves out {off} (NNIK_GC_{off.upper()})")
    if c in noted_line:
        b.noted_line = noted_line[c]
    elif c in MOTION:
        _set(b, "motion", MOTION[c])
    elif c in NONMODAL:
        _set(b, "nonmodal", NONMODAL[c])
    elif c in PLANE:
        _set(b, "plane", PLANE[c])
    elif c in UNITS:
        _set(b, "inch", UNITS[c])
    elif c in DISTANCE:
        _set(b, "relative", DISTANCE[c])
    elif c in ARC_DISTANCE:
        _set(b, "arc_abs", ARC_DISTANCE[c])
    elif c in FEED_MODE:
        _set(b, "inverse_time", FEED_MODE[c])
    elif c in TLO:
        _set(b, "tlo", TLO[c])
        if c == 430:
            b.noted.append("G43")
    elif c in WCS:
        _set(b, "wcs", WCS[c])
    elif c in G_QUIET:
        pass
    elif c in G_NOTED_WORD:
        b.noted.append(G_NOTED_WORD[c])
    elif c in PROBING:
        raise GcodeLineError(43, name)
    elif c in CANNED:
        raise GcodeLineError(20, f"{name} (a canned cycle)")
    elif c in (591, 592, 593):
        raise GcodeLineError(29, name)
    elif c % 10 and (c - c % 10) in {**MOTION, **NONMODAL, **PLANE, **UNITS, **DISTANCE, **FEED_MODE, **WCS}:
        raise GcodeLineError(23, name)
    else:
        raise GcodeLineError(20, name)


def _m(b: Block, n: Num, marlin: bool, m300_pen: bool) -> bool:
    """An M word; True when it makes the whole line noted (the rest is its arguments)."""
    c = n.code10
    name = f"M{n.ip}" + (f".{c % 10}" if c % 10 else "")
    if n.neg:
        raise GcodeLineError(20, name)
    if c in M_STOP:
        _set(b, "stop", M_STOP[c])
    elif c in M_SPINDLE:
        _set(b, "spindle", M_SPINDLE[c])
    elif c in M_COOLANT:
        _set(b, "coolant", M_COOLANT[c])
    elif c == 60:
        b.m6 = True
        b.noted.append("M6")
    elif c == 4000:
        b.wait = True
    elif c in (820, 830):
        _set(b, "e_relative", int(c == 830))
    elif c == 3000 and m300_pen:
        b.m300 = True
    elif c in M_FLOW:
        raise GcodeLineError(42, name)
    else:
        b.noted_line = name
        return True
    return False


def parse_block(s: str, marlin: bool = False, m300_pen: bool = False, features=FEATURES) -> Block:
    """The words of a cleaned line (upper case, no blanks); GcodeLineError names what is wrong.
    marlin: E words, G4 P in ms, Marlin's setup G codes noted; m300_pen: M300 S moves a pen."""
    b = Block()
    i = 0
    while i < len(s):
        letter = s[i]
        i += 1
        if letter in "#[]":
            raise GcodeLineError(41, letter)
        if not "A" <= letter <= "Z":
            raise GcodeLineError(1, repr(letter))
        if letter == "O":
            if i < len(s) and s[i] == "<":
                raise GcodeLineError(42, "O<name>")
            _, i = scan_num(s, i)
            if i < len(s):
                raise GcodeLineError(42, "an O word with more on its line")
            b.noted.append("O")
            continue
        n, i = scan_num(s, i)
        if letter == "G":
            _g(b, n, marlin, features)
            b.used |= {f for f, codes in FEATURE_CODES.items() if n.code10 in codes}
            if b.noted_line:
                break
        elif letter == "M":
            if _m(b, n, marlin, m300_pen):
                break
        elif letter == "N":
            if n.neg:
                raise GcodeLineError(4, "N")
            if n.ip > LINE_NUMBER_MAX:
                raise GcodeLineError(27)
        elif letter in VALUE_LETTERS:
            if letter == "E" and not marlin:
                raise GcodeLineError(20, "E (extrusion): the file is not read as Marlin's")
            if letter in b.values:
                raise GcodeLineError(25, letter)
            b.values[letter] = n
        elif letter in EXTRA_AXES:
            raise GcodeLineError(20, f"axis {letter}: the machine has X and Y")
        else:
            raise GcodeLineError(20, f"word {letter}")
    if b.noted_line and (b.motion is not None or b.nonmodal is not None or any(a in b.values for a in "XYZ")):
        raise GcodeLineError(20, f"{b.noted_line} on a line that moves")
    return b
