"""The G-code parser: numbers to whole micrometres and the firmware's error texts."""

from __future__ import annotations

import pytest

from nnik.firmware.gcode.parse import GcodeLineError, Num, parse_line, split_lines


def um(text: str, inch: bool = False) -> int:
    return parse_line(f"X{text}").values["X"].to_um(inch)


@pytest.mark.parametrize("text, inch, want", [
    ("10", False, 10000), ("-2.351", False, -2351), ("0.0005", False, 1), ("-0.0005", False, -1),
    ("0.00049", False, 0), (".5", False, 500), ("+3.", False, 3000), ("9999.99999", False, 10000000),
    ("1.000000", False, 1000), ("0.000020", True, 1), ("0.000019", True, 0), ("9999.999999", True, 254000000),
    ("1", True, 25400), ("0.0025", True, 64), ("-0.0025", True, -64), ("0.00001", True, 0),
])
def test_numbers_round_half_away_from_zero(text, inch, want):
    assert um(text, inch) == want


def test_words_modes_and_comments():
    w = parse_line("n10 g91 G20 (inch, relative) g2 x1 y-2 i3 j4 f100 ; done")
    assert (w.motion, w.inch, w.relative, w.wait) == (2, True, True, False)
    assert sorted(w.values) == ["F", "I", "J", "X", "Y"]
    assert parse_line("M400").wait and parse_line("").values == {}
    assert Num(False, True, 1, 5, 1).to_um(False) == 1500


@pytest.mark.parametrize("line, msg", [
    ("G1 Z5", "unsupported word Z"),
    ("G18 G1 X1", "unsupported G18"),
    ("G93", "unsupported G93"),
    ("G55", "unsupported G55"),
    ("G28.1", "unsupported G28.1"),
    ("G4 G92 X1", "two non-modal commands"),
    ("M0", "M0 pause not supported"),
    ("m1", "M1 pause not supported"),
    ("M7", "unsupported M7"),
    ("N", "bad number after N"),
    ("N123456789 G1 X1", "number too large after N"),
    ("N10 G1 X1 *", "bad checksum"),
    ("N10 G1 X1 *1000", "bad checksum"),
    ("N10 G1 X1 *256", "bad checksum"),
    ("N10 G1 X1 *12 G1", "bad checksum"),
    ("N10 G1 X1*0", "checksum mismatch"),
    ("G1.5 X1", "unsupported G1.5"),
    ("G1.25 X1", "G needs a whole number"),
    ("G1 X", "bad number after X"),
    ("G1 X-.", "bad number after X"),
    ("G1 X10000", "number too large after X"),
    ("G1 X1.1234567", "too many decimals after X"),
    ("G1 X1 X2", "repeated word X"),
    ("G0 G1 X1", "two motion commands"),
    ("G1 X1 (open", "unterminated comment"),
    ("G1 X1 #", "unexpected character"),
    ("X" + "1" * 95, "line too long"),
])
def test_errors_name_the_problem(line, msg):
    with pytest.raises(GcodeLineError) as e:
        parse_line(line)
    assert str(e.value) == msg


def marlin(line: str) -> str:
    """line + '*' + the XOR of its bytes, as a Marlin host sends it."""
    x = 0
    for c in line.encode("latin-1"):
        x ^= c
    return f"{line}*{x}"


def test_line_numbers_checksums_and_grbl_modes():
    w = parse_line(marlin("N12345678 G17 G40 G49 G80 G94 G54 G64 G1 x1") + " \r")
    assert w.motion == 1 and w.values["X"].to_um(False) == 1000
    assert marlin("N1 G1") == "N1 G1*41"  # 0x4E ^ 0x31 ^ 0x20 ^ 0x47 ^ 0x31, by hand
    # a '*' inside a comment is no checksum; the checksum covers the comment before it
    assert parse_line("G1 X1 (a*b) ; c*d").values["X"].ip == 1
    assert parse_line(marlin("N2 G1 (here) X1")).values["X"].ip == 1
    with pytest.raises(GcodeLineError, match="checksum mismatch"):
        parse_line(marlin("N2 G1 X1").replace("X1", "X2"))
    assert parse_line(" % (start)").values == {}  # a CAM post's first and last line
    w = parse_line("G4 P0.5")
    assert w.nonmodal == 4 and w.values["P"].to_um(False) == 500
    assert parse_line("M30").end and not parse_line("M400").end


def test_split_lines_keeps_bytes_and_drops_the_last_newline():
    assert split_lines(b"G1 X1\r\n\nG1 Y\xe9\n") == ["G1 X1\r", "", "G1 Y\xe9"]


def test_the_scenarios_tool_table_reaches_the_machine_and_the_library_header(tmp_path):
    """[tool] in the scenario (issue 20): the firmware's machine and the exported config header
    carry it; a job's '; nnik-machine:' comment still overrides it."""
    from jinja2 import Environment, FileSystemLoader

    from nnik.firmware.config import default_machine
    from nnik.firmware.gcode.job import job_machine
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
    assert job_machine(["; nnik-machine: tool=laser"], cfg, "j").tool == "laser"


def test_a_bad_tool_table_is_one_line(tmp_path, capsys):
    from tests.bad_input import GALVO, fails

    toml = tmp_path / "t.toml"
    toml.write_text(GALVO + '\n[tool]\nkind = "plasma"\n')
    fails(capsys, ["generate", toml, "-o", tmp_path / "o"], "[tool] kind", "laser, pen, servo")
