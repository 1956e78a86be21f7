"""Property: any job of the accepted dialect steps the same on the simulated Uno as in the Python
model, on both machine kinds. hypothesis draws the jobs (and shrinks a failing one): lines and
rapids, I/J arcs ending in every quadrant and full circles, R arcs short and long (semicircles
at the end tolerance too), both directions, G90/G91, G20/G21, comments, a few bad lines, and
endings with and without M400/M2/M30; and every grbl word mixed in: N numbers with and without
Marlin checksums, '%', the accepted modal words, G92, G28 (with and without axes), G4 P, and the
tool: M3/M4/M5 with S on the laser build, Z up and down on a servo pen build, every tool change
on the same segment and tick on the chip.

CI runs NNIK_HYPOTHESIS_EXAMPLES (default 10) jobs per machine; `make bench` runs more. Jobs stay
short in simulated time: at most 5 moves of a few mm at 2-9 m/min."""

from __future__ import annotations

import math
import os

import pytest
from hypothesis import HealthCheck, event, given, note, settings
from hypothesis import strategies as st

from dataclasses import replace

from nnik.firmware.config import MachineConfig, default_machine
from nnik.firmware.gcode.motion import Interpreter
from tests.firmware.gcode.conftest import run_both

EXAMPLES = int(os.environ.get("NNIK_HYPOTHESIS_EXAMPLES", "10"))
UM_PER = {False: 1000, True: 25400}  # um per program unit: mm, inch
BAD_LINES = ["G2 X30 R1", "G3 R2", "G1 X1 R1", "G2 X1 I1 R1", "G2 X1 Y1", "G1 Z1", "G2 X0 Y0 I0 J0", "G18", "M0",
             "G92", "G4", "S-1", "M3 M5", "N1 G1 X1*0", "G28.1", "G92 G1 X1"]
MODAL = ["G17", "G40", "G49", "G54", "G64", "G80", "G94"]


def with_checksum(line: str) -> str:
    x = 0
    for c in line.encode("latin-1"):
        x ^= c
    return f"{line}*{x}"


def num(um: float, inch: bool) -> str:
    """A coordinate in program units with the decimals the firmware takes."""
    return f"{um / UM_PER[inch]:.5f}" if inch else f"{um / 1000:.3f}"


def comment(draw, text: str) -> str:
    how = draw(st.sampled_from(["", "", "", "paren", "semi", "lower"]))
    if how == "paren":
        return f"(move) {text}"
    if how == "semi":
        return f"{text} ; note"
    return text.lower() if how == "lower" else text


@st.composite
def jobs(draw, pen: bool = False) -> list[str]:
    """Lines of a job; an Interpreter follows them so every move starts where the last ended."""
    it = Interpreter(MachineConfig(origin_um=(0, 0), tool="servo" if pen else "laser", pen_z_um=250))
    lines: list[str] = []

    def add(text: str) -> None:
        n = draw(st.sampled_from(["", "", "n", "sum"]))
        if n:
            text = f"N{draw(st.integers(0, 99999999))} {text}"
            text = with_checksum(text) if n == "sum" else text
        lines.append(text)
        it.line(text)

    def tool_word() -> str:
        if pen:
            return draw(st.sampled_from([f"Z{draw(st.integers(-10, 30)) / 10:.1f}", "", "M3 S100", "M5"]))
        return draw(st.sampled_from(["", f"S{draw(st.integers(0, 1200))}", "M3", "M4", "M5",
                                     f"M3 S{draw(st.integers(0, 1000))}", f"M4 S{draw(st.integers(0, 1000))}"]))

    def grbl_word() -> None:
        x, y = (f"{draw(st.integers(-5000, 5000)) / 1000:.3f}" for _ in range(2))
        add(draw(st.sampled_from([f"G92 X{x} Y{y}", f"G92 X{x}", "G28", f"G28 X{x}", f"G91 G28 Y{y}", "G90",
                                  f"G4 P{draw(st.integers(0, 40)) / 1000:.3f}", " ".join(draw(st.lists(
                                      st.sampled_from(MODAL), min_size=1, max_size=3, unique=True))), "%",
                                  tool_word() or "M5", "M2"])))

    add(f"G21 G90 F{draw(st.integers(2000, 9000))}")
    for _ in range(draw(st.integers(1, 5))):
        inch, rel, (x0, y0) = it.inch, it.relative, tuple(it.mp[:2])
        if draw(st.integers(0, 2)) == 0:
            grbl_word()
            inch, rel, (x0, y0) = it.inch, it.relative, tuple(it.mp[:2])
        kind = draw(st.sampled_from(["line", "line", "rapid", "ij", "ij", "circle", "r", "r", "modes", "bad"]))
        modes = ""
        if kind == "modes" or draw(st.integers(0, 4)) == 0:
            inch, rel = draw(st.booleans()), draw(st.booleans())
            modes = f"G{20 if inch else 21} G{91 if rel else 90} "
            if kind == "modes":
                add(modes.strip())
                continue

        def xy(x: float, y: float) -> str:
            if rel:
                x, y = x - x0, y - y0
            return f"X{num(x, inch)} Y{num(y, inch)}"

        if kind in ("line", "rapid"):
            x, y = draw(st.integers(-8000, 8000)), draw(st.integers(-8000, 8000))
            text = f"G{0 if kind == 'rapid' else 1} {xy(x, y)}"
        elif kind in ("ij", "circle"):  # centre at r from the start, end anywhere on the circle
            r = draw(st.integers(300, 3000))
            a0, a1 = (math.radians(draw(st.integers(0, 359))) for _ in range(2))
            cx, cy = x0 - r * math.cos(a0), y0 - r * math.sin(a0)
            ij = f"I{num(cx - x0, inch)} J{num(cy - y0, inch)}"
            g = draw(st.sampled_from(["G2", "G3"]))
            if kind == "circle":
                text = f"{g} {ij}" if draw(st.booleans()) else f"{g} {xy(x0, y0)} {ij}"
            else:
                text = f"{g} {xy(round(cx + r * math.cos(a1)), round(cy + r * math.sin(a1)))} {ij}"
        elif kind == "r":  # chord d, |R| from d/2 (a semicircle, at the tolerance) up
            d = draw(st.integers(300, 5000))
            a = math.radians(draw(st.integers(0, 359)))
            x, y = round(x0 + d * math.cos(a)), round(y0 + d * math.sin(a))
            long_way = draw(st.booleans())
            rad = d / 2 * draw(st.sampled_from([1.0, 1.0001, 1.05, 1.5] + ([] if long_way else [3.0])))
            text = f"{draw(st.sampled_from(['G2', 'G3']))} {xy(x, y)} R{'-' if long_way else ''}{num(rad, inch)}"
        else:
            text = draw(st.sampled_from(BAD_LINES))
        event(f"{kind}{' G20' if inch else ''}{' G91' if rel else ''}")
        tw = tool_word() if kind != "bad" else ""
        add(comment(draw, modes + text + (" " + tw if tw else "")))
    ending = draw(st.sampled_from(["", "M400", "M2", "M30"]))
    event(f"ending {ending or 'none'}")
    if ending:
        add(ending)
    return lines


@pytest.mark.parametrize("scenario", ["galvo_cba2012", "corexy_nonlinear"])
@settings(max_examples=EXAMPLES, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(lines=jobs())
def test_random_jobs_step_the_same_on_the_chip(firmware, scenario, lines):
    note("\n".join(lines))
    run_both(firmware[scenario], lines)


@settings(max_examples=EXAMPLES, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(lines=jobs(pen=True))
def test_random_pen_jobs_step_the_same_on_the_chip(corexy_run, tool_firmware, lines):
    from nnik.firmware.ik_oracle import load_scenario_of

    note("\n".join(lines))
    cfg = replace(default_machine(load_scenario_of(corexy_run)), tool="servo", pen_z_um=250, bounds_um=None)
    run_both(tool_firmware(cfg), lines)  # random jobs wander beyond the travel: soft limits off
