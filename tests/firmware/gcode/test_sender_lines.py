"""The character-counting sender's lines (nnik.firmware.gcode.simrun.sender_line): whitespace and
comments out, as grbl's stream.py and grbl-streamer send them, and never a line the firmware's
reader would read otherwise: the model of the lines sent is the model of the file's."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.chip import sent_lines
from nnik.firmware.gcode.motion import interpret
from nnik.firmware.gcode.reader import read_line, sendable
from nnik.firmware.gcode.simrun import sender_line
from tests.firmware.gcode.random_gcode import WORDS_BAD, WORDS_NOTED, random_lines


def read(s: str):
    return read_line(sendable(s.encode("latin-1")))


def test_comments_and_blanks_go():
    assert sender_line("G01 Z-0.125000 F100.0(Penetrate)") == "G01Z-0.125000F100.0"
    assert sender_line("(Start cutting path id: path815)") == ""
    assert sender_line("   ") == "" and sender_line("G1 X1 ; to the corner") == "G1X1"
    assert sender_line("G1X1") == "G1X1"


pieces = st.sampled_from(WORDS_BAD + WORDS_NOTED + ["G1 X1.5 Y-2", "g0x3y4", "G2 X1 Y1 I1 J0", "M3 S500", "%",
                                                      "G4 P0.1", "N7 G1 X2*", "(a (nested) one)", "(open", ";",
                                                      "( x ) G1 X1", "G1 (x) X2 ; y", "\t G1\tX3 \t"])


@settings(max_examples=300, deadline=None)
@given(st.lists(pieces, min_size=1, max_size=4), st.integers(0, 10_000))
def test_the_reader_reads_what_was_sent_as_the_file(parts, seed):
    line = " ".join(parts).encode("utf-8").decode("latin-1")  # a job's bytes as `nnik job` reads them
    assert read(sender_line(line)) == read(line)
    assert len(sender_line(line)) <= len(line)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_the_model_of_the_lines_sent_is_the_files(seed):
    cfg = MachineConfig(origin_um=(0, 0))
    lines = random_lines(40, seed)
    a, b = interpret(lines, cfg), interpret(sent_lines(lines, "counting"), cfg)
    assert a.replies == b.replies and a.ends == b.ends
    assert sent_lines(lines, "send-response") == lines
