"""Reading the simavr harness (nnik/firmware/gcode/simrun.py): the binary event records and
which firmware lines answer a line sent (the old texts and grbl's)."""

from __future__ import annotations

import numpy as np

from nnik.firmware.gcode import chip
from nnik.firmware.gcode.simrun import EVENT, is_answer, read_events


def test_answers_are_ok_and_errors_in_both_dialects():
    for text in ("ok", "error: line 3: unsupported word Z", "error:20", "ok "):
        assert is_answer(text)
    for text in ("Grbl 1.1h ['$' for help]", "nnik galvo ready", "[MSG:Caution: Unlocked]", "", "PASS 64 vectors"):
        assert not is_answer(text)


def test_binary_events_split_as_the_text_lines_did(tmp_path):
    rec = [(10, "B", 1), (20, "M", 0), (25, "S", 0 | 1 << 1), (26, "S", 1), (30, "T", 128), (40, "B", 0),
           (50, "B", 1), (60, "S", 1 | 1 << 1), (70, "B", 0), (80, "B", 1)]
    ev = np.array([(c, ord(t), v) for c, t, v in rec], dtype=EVENT)
    path = tmp_path / "ev.bin"
    ev.tofile(path)
    steps, marks, busy, tool = read_events(path)
    text = "\n".join(f"S {c} {v & 1} {v >> 1}" if t == "S" else f"M {c}" if t == "M" else f"{t} {c} {v}"
                     for c, t, v in rec) + "\nE 90 done 0\n"
    want = chip.parse_events(text)
    assert np.array_equal(steps, want.steps) and steps.tolist() == [[25, 0, 1], [26, 1, 0], [60, 1, 1]]
    assert np.array_equal(marks, want.marks) and np.array_equal(tool, want.tool)
    assert np.array_equal(busy, want.busy) and busy.tolist() == [[10, 40], [50, 70]]  # the last rise: no fall
    for a in (steps, marks, busy, tool):
        assert a.dtype == np.int64


def test_an_empty_event_file_reads_as_no_events(tmp_path):
    path = tmp_path / "ev.bin"
    path.write_bytes(b"")
    steps, marks, busy, tool = read_events(path)
    assert steps.shape == (0, 3) and marks.shape == (0,) and busy.shape == (0, 2) and tool.shape == (0, 2)


def test_the_mega_builds_with_its_own_variant_and_limits():
    assert chip.mcu_of("atmega2560").variant == "mega" and chip.mcu_of("atmega328p").variant == "standard"
    assert "-mmcu=atmega2560" in chip.common_flags("atmega2560") and "-DARDUINO_AVR_MEGA2560" in chip.common_flags("atmega2560")
    assert chip.MCUS["atmega2560"].ram_bytes == 8192 and chip.FLASH_BYTES == 32 * 1024 - 512
