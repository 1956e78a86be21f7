"""Random G-code lines over the whole dialect (good and bad), for the host-vs-model and chip
tests: every word class the reader and parser know, in grbl's and Marlin's forms."""

from __future__ import annotations

import numpy as np

WORDS_BAD = ["G1 X1 X2", "G1 X", "G1 X--1", "#<a>=1", "o100 sub", "O200 call", "G38.2 Z-1", "G31 X1", "G81 X1 Y1 Z-1",
             "G41 D1", "G68 R30", "A5", "G1.5 X1", "G28.15", "M98 P100", "G1 X1 [2]", "G59.1", "G10 L3 P1 X0",
             "G10 L2 P9 X1", "G10 L2 X1", "G4", "G4 P-1", "G1 F0 X1", "G2 X1", "G2 I1", "G2 X3 Y0 I1 J0", "G0 R1 X1",
             "G53 G2 X1 I1", "G80 X1", "G0 G28 X1", "G43.1", "T300", "S-5", "N-1 G1", "N20000000 G0", "G5 X1 Y1",
             "G1 X1 *", "G1 X1 *256", "G1 X1 *12 3", "x" * 90, "G1 X1234567890", "E5", "M300", "G18 G2 X1 Y1 I1"]
WORDS_NOTED = ["M104 S200", "M140 S60", "M106 S255", "M107", "M117 Hello world", "M862.3 P \"MK3S\"", "M73 P10 R5",
               "G29", "M555 X1 Y2 W3 H4", "M62 P1", "M201 X1000 Y1000", "M84", "M17", "M18", "T1 M6", "M7", "M8",
               "M9", "M1", "G64 P0.01", "G61", "G61.1", "G40", "G49", "G43 H1", "O1000", "%", "% header text", "$H",
               "$32=1", "G98", "G99", "G69", "G15", "G97", "(comment)", "; comment", "", "/G0 X1", "\ufeff(bom)"]


def _num(rng, lo, hi, decimals=None) -> str:
    d = int(rng.integers(0, 7)) if decimals is None else decimals
    v = rng.uniform(lo, hi)
    text = f"{v:.{d}f}"
    if rng.random() < 0.1 and "." in text:  # grbl reads .5 and 5. too
        text = text.rstrip("0") or "0"
        if text.startswith("0.") and rng.random() < 0.5:
            text = text[1:]
        elif text.startswith("-0.") and rng.random() < 0.5:
            text = "-" + text[2:]
    return text


def random_lines(n: int, seed: int, span: float = 20.0, marlin: bool = False) -> list[str]:
    rng = np.random.default_rng(seed)
    out: list[str] = []
    for _ in range(n):
        k = int(rng.integers(0, 20))
        x, y = (_num(rng, -span, span) for _ in range(2))
        f = _num(rng, 100, 12000, 1)
        if k <= 4:
            out.append(f"G{rng.integers(0, 2)} X{x} Y{y} F{f}")
        elif k == 5:
            out.append(f"G91 G1 X{_num(rng, -2, 2)} Y{_num(rng, -2, 2)}")
            out.append("G90")
        elif k == 6:  # a full turn, a half turn, an R arc
            i, j = _num(rng, -5, 5), _num(rng, -5, 5)
            g = rng.integers(2, 4)
            out.append(rng.choice([f"G{g} X{x} Y{y} I{i} J{j}", f"G{g} X0 Y0 R{_num(rng, 1, 30)}",
                                   f"G91 G{g} X0 Y0 I{i} J{j}", f"G{g} X{x} Y{y} R-{_num(rng, 1, 30)}"]))
            out.append("G90")
        elif k == 7:
            out.append(rng.choice(["G20", "G21", "G90.1", "G91.1", "G17", "G18", "G19", "G93", "G94", "G54", "G55",
                                   "M400", "G92.1", "G28.1", "G30.1", "G49", "G80"]))
        elif k == 8:
            out.append(rng.choice([f"G10 L2 P{rng.integers(0, 7)} X{x} Y{y}", f"G10 L20 P{rng.integers(0, 7)} X{x}",
                                   f"G92 X{x} Y{y}", f"G92 Z{_num(rng, -2, 2)}", "G28", f"G28 X{x}", "G30",
                                   f"G91 G28 Z0", f"G53 G0 X{x} Y{y}", f"G43.1 Z{_num(rng, -1, 1)}"]))
        elif k == 9:
            out.append(rng.choice([f"M3 S{rng.integers(0, 20000)}", f"M4 S{_num(rng, 0, 1200)}", "M5", "S0",
                                   f"S{rng.integers(0, 1000)}", f"G4 P{_num(rng, 0, 0.05, 3)}", f"G1 Z{_num(rng, -2, 2)}",
                                   f"G0 Z{_num(rng, -2, 2)} X{x}", f"M300 S{rng.choice([30, 50])}"]))
        elif k == 10:
            out.append(rng.choice(WORDS_NOTED))
        elif k == 11:
            out.append(rng.choice(WORDS_BAD))
        elif k == 12:  # G5: a curve, or its continuation
            out.append(rng.choice([f"G5 I{_num(rng, -5, 5)} J{_num(rng, -5, 5)} P{_num(rng, -5, 5)} Q{_num(rng, -5, 5)} X{x} Y{y}",
                                   f"G5 P{_num(rng, -5, 5)} Q{_num(rng, -5, 5)} X{x} Y{y}"]))
        elif k == 13:  # arcs in other planes (planar: the linear axis stays)
            out.append(rng.choice([f"G18 G2 X{x} Z0 I{_num(rng, -3, 3)} K{_num(rng, -3, 3)}",
                                   f"G19 G3 Y{y} Z0 J{_num(rng, -3, 3)} K1", "G17"]))
        elif k == 14:  # inverse time
            out.append(f"G93 G1 X{x} Y{y} F{_num(rng, 1, 200, 2)}")
            out.append("G94")
        elif k == 15 and marlin:
            e = _num(rng, -1, 5, 5)
            out.append(rng.choice([f"G1 X{x} Y{y} E{e}", f"G1 E{e} F2400", "G92 E0", "M82", "M83", f"G0 X{x} Y{y}",
                                   f"G4 S{_num(rng, 0, 0.02, 3)}", f"G4 P{rng.integers(0, 30)}"]))
        elif k == 16:  # packed, lower case, blanks and comments in odd places
            out.append(rng.choice([f"g1x{x}y{y}", f"G1X{x}Y{y}S{rng.integers(0, 1000)}M3", f"N{rng.integers(0, 99999)} G0 X{x}",
                                   f"G1 X{x} (a) Y{y} ; b", f"G1 X{x}\tY{y}", f"G0 X {x} Y {y}", f"G0 G90 G40 G21 G17 G94 G80",
                                   f"G1 X{x} /Y{y}", f"(unterminated G1 X{x}"]))
        elif k == 17:
            line = f"N{rng.integers(0, 1000)} G1 X{x} Y{y}"
            cs = 0
            for c in line.encode():
                cs ^= c
            out.append(rng.choice([f"{line}*{cs}", f"{line}*{(cs + 1) % 256}"]))
        else:
            out.append(f"G1 X{x} Y{y}")
    return out
