"""The reader (grbl's protocol layer) and the words (grbl's parser, widened for real files):
numbers to whole micrometres, comments, line length, checksums, grbl's error numbers."""

from __future__ import annotations

import pytest

from nnik.firmware.gcode.codes import GcodeLineError
from nnik.firmware.gcode.parse import Num, parse_block
from nnik.firmware.gcode.reader import DOLLAR, EMPTY, ERROR, LINE, read_line, sendable, split_lines


def words(line: str, **kw):
    rd = read_line(sendable(line.encode("utf-8")))
    assert rd.kind == LINE, rd
    return parse_block(rd.text, **kw)


def um(text: str, inch: bool = False) -> int:
    return words(f"X{text}").values["X"].to_um(inch)


@pytest.mark.parametrize("text, inch, want", [
    ("10", False, 10000), ("-2.351", False, -2351), ("0.0005", False, 1), ("-0.0005", False, -1),
    ("0.00049", False, 0), (".5", False, 500), ("+3.", False, 3000), ("9999.99999", False, 10000000),
    ("1.000000", False, 1000), ("0.000020", True, 1), ("0.000019", True, 0), ("9999.999999", True, 254000000),
    ("1", True, 25400), ("0.0025", True, 64), ("-0.0025", True, -64), ("0.00001", True, 0),
    ("1.12345678", False, 1123), ("123456789", False, 1 << 28), ("-99999", True, -(1 << 28)),
])
def test_numbers_round_half_away_from_zero_and_saturate(text, inch, want):
    assert um(text, inch) == want


def test_the_reader_drops_what_grbl_drops():
    assert read_line(b"n10 g91 G20 (inch, relative) g2 x1 y-2 i3 j4 f100 ; done").text == "N10G91G20G2X1Y-2I3J4F100"
    assert read_line(b"G1 X1 (a) Y2 (b").text == "G1X1Y2"  # an open '(' runs to the end, as grbl
    assert read_line(b"G1 X1 (a ; b) Y2").text == "G1X1Y2"  # ';' inside '(' ... ')' is no comment
    assert read_line(b"/G0 X1").text == "G0X1" and read_line(b"G0\tX1").text == "G0X1"
    assert read_line(sendable("\ufeff(BOM)G0 X1".encode())).text == "G0X1"
    assert read_line(sendable(b"G0 X1 (why?! ~)")).text == "G0X1"  # realtime bytes never reach it
    for empty in (b"", b"  ", b"(only a comment)", b"; a comment", b"%", b"% program 1000 by CAM"):
        assert read_line(empty).kind == EMPTY
    assert read_line(b"$H").kind == DOLLAR and read_line(b"$$").text == "$$"
    assert read_line(b"(" + b"x" * 300 + b") G0 X1").text == "G0X1"  # a long comment is no error
    assert read_line(b"X" + b"1" * 78).kind == LINE and read_line(b"X" + b"1" * 79).code == 11  # 79 characters


def test_words_and_groups():
    b = words("N10 G91 G20 G2 X1 Y-2 I3 J4 F100")
    assert (b.motion, b.inch, b.relative) == (2, 1, 1) and sorted(b.values) == ["F", "I", "J", "X", "Y"]
    assert words("M400").wait and words("G0X0Y0S8000M3").spindle == 3
    safety = words("G0 G90 G40 G21 G17 G94 G80")  # a Fanuc safety block: the last motion word wins
    assert safety.motion == 80 and safety.last_wins == 1
    assert Num(False, 1, 5, 1).to_um(False) == 1500
    assert words("M104 S200").noted_line == "M104" and words('M862.3 P "MK3S"').noted_line == "M862.3"
    assert words("T1 M6").noted == ["M6"] and words("G64 P0.01").noted == ["G64"]
    assert words("O1000").noted == ["O"] and words("G43 H1").tlo == 2
    assert words("M300 S30", m300_pen=True).m300 and words("M300 S440 P200").noted_line == "M300"
    assert words("G1 X1 E0.5", marlin=True).values["E"].to_um() == 500
    assert words("G10 S1", marlin=True).noted_line == "G10"  # Marlin's retract, not grbl's offsets


@pytest.mark.parametrize("line, code", [
    ("G1 X1 X2", 25), ("G1 X", 2), ("G1 X--1", 2), ("G1 X-.", 2), ("G1 X1234567890", 2), ("#<a>=1", 41),
    ("G1 X[1+2]", 41), ("o100 sub", 42), ("O<loop> while [#1 lt 3]", 42), ("O200 call", 42), ("M98 P100", 42),
    ("G38.2 Z-1", 43), ("G31 X1", 43), ("G81 X1 Y1 Z-1 R1", 20), ("G41 D1", 20), ("G68 X0 Y0 R30", 20), ("A5", 20),
    ("G1 B1", 20), ("G1.5 X1", 23), ("G1.25 X1", 23), ("G59.1", 29), ("G7", 20), ("1 X1", 1), ("N-1 G1", 4),
    ("N20000000 G0", 27), ("E5", 20), ("G1 X1 M104 S1", 20),
])
def test_refusals_name_grbls_number(line, code):
    with pytest.raises(GcodeLineError) as e:
        words(line)
    assert e.value.code == code and str(e.value).startswith(f"error:{code} ")


def marlin(line: str) -> str:
    """line + '*' + the XOR of its bytes, as a Marlin host sends it."""
    x = 0
    for c in line.encode("latin-1"):
        x ^= c
    return f"{line}*{x}"


def test_checksums():
    assert marlin("N1 G1") == "N1 G1*41"  # 0x4E ^ 0x31 ^ 0x20 ^ 0x47 ^ 0x31, by hand
    assert read_line(marlin("N12345 G1 x1").encode() + b" \t").text == "N12345G1X1"
    assert read_line(b"G1 X1 (a*b) ; c*d").text == "G1X1"  # a '*' in a comment is no checksum
    for bad, code in ((b"N10 G1 X1 *", 39), (b"N10 G1 X1 *1000", 39), (b"N10 G1 X1 *256", 39), (b"G1 X1 *12 3", 39),
                      (b"N10 G1 X1*0", 40)):
        assert read_line(bad).code == code, bad


def test_split_lines_takes_lf_crlf_and_cr_alone():
    assert split_lines(b"G1 X1\r\n\nG1 Y\xe9\n") == [b"G1 X1", b"", b"G1 Y\xe9"]
    assert split_lines(b"G0 X1\rG0 X2\rG0 X3") == [b"G0 X1", b"G0 X2", b"G0 X3"]
    assert split_lines(b"G0 X1\r\nG0 X2\nG0 X3\r") == [b"G0 X1", b"G0 X2", b"G0 X3"]


def test_the_scenarios_tool_table_reaches_the_machine_and_the_library_header(tmp_path):
    """[tool] in the scenario (issue 20): the firmware's machine and the exported config header
    carry it (a job's comments do not: `nnik job --tool` does)."""
    from jinja2 import Environment, FileSystemLoader

    from nnik.firmware.config import default_machine
    from nnik.machine.scenario import load_scenario
    from tests.conftest import DATASETS, ROOT

    text = (DATASETS / "corexy_nonlinear.toml").read_text() + (
        '\n[tool]\nkind = "servo"\npen_z_um = 300\nservo_up_deg = 100\nservo_down_deg = 20\n')
    toml = tmp_path / "pen.toml"
    toml.write_text(text)
    scn = load_scenario(toml)
    cfg = default_machine(scn)
    assert (cfg.tool, cfg.pen_z_um, cfg.servo_up_deg, cfg.servo_down_deg) == ("servo", 300, 100, 20)
    assert scn.fingerprint == load_scenario(DATASETS / "corexy_nonlinear.toml").fingerprint  # no retraining
    env = Environment(loader=FileSystemLoader(ROOT / "codegen" / "arduino" / "templates"))
    h = env.get_template("gcode_config.h.j2").render(name="m", origin=[0, 0], seg_um=500, tick_hz=10000,
                                                     rapid_um_min=1, feed_um_min=1, tool=cfg.tool,
                                                     tool_defines=cfg.defines())
    for key, value in cfg.defines().items():
        assert f"#ifndef {key}\n#define {key} {value} " in h
    assert "#define NNIK_GC_TOOL 1 " in h and "#define NNIK_GC_TOOL_CS 7 " in h


def test_a_bad_tool_table_is_one_line(tmp_path, capsys):
    from tests.bad_input import GALVO, fails

    toml = tmp_path / "t.toml"
    toml.write_text(GALVO + '\n[tool]\nkind = "plasma"\n')
    fails(capsys, ["generate", toml, "-o", tmp_path / "o"], "[tool] kind", "laser, pen, servo, spindle, knife, none")
