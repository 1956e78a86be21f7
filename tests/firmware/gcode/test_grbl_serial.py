"""grbl 1.1's serial interface, spoken by the G-code firmware on a simulated Uno whose UART is a
pseudo-terminal (pyserial on /dev/pts/N, simulated time held to wall time)."""

from __future__ import annotations

import time

import pytest

from nnik.firmware.gcode.pty_chip import PtyChip
from tests.firmware.gcode.grbl_pty import BANNER, GrblPort, grbl_firmware  # noqa: F401 (fixture)


@pytest.fixture
def uno(grbl_firmware, tmp_path):
    with PtyChip(grbl_firmware[2], tmp_path) as chip:
        port = GrblPort(chip.path)
        try:
            port.banner()  # opening the terminal resets the chip, as a Uno's DTR does
            yield port, chip
        finally:
            port.close()


def test_banner_ok_and_errors(uno):
    port, _ = uno
    assert port.cmd("G21 G90") == ["ok"]
    assert port.cmd("") == ["ok"]  # grbl answers empty and comment lines too
    assert port.cmd("(a comment) ; and another") == ["ok"]
    assert port.cmd("G7") == ["error:20"]  # unsupported command (lathe diameter mode)
    assert port.cmd("G1 X" + "1" * 80) == ["error:11"]  # more than 79 characters after cleaning
    assert port.cmd("g0 x1 y1 (lower case, comments) ") == ["ok"]
    port.write(b"\x18")
    assert port.banner()[-1] == BANNER


def test_status_reports_idle_and_during_motion(uno, grbl_firmware):
    port, _ = uno
    depth = grbl_firmware[1]["machine"].lookahead  # the chip's planner depth (ranges.plan_blocks_for)
    m = port.status()
    assert m.group(1) == "Idle" and m.group(2, 3, 4) == ("0.000", "0.000", "0.000")
    assert m.group(5, 6) == (str(depth), "128") and m.group(9)  # Bf: planner blocks and RX bytes free; WCO first
    assert port.cmd("G1 X40 F3000") == ["ok"]
    seen = []
    for _ in range(200):
        m = port.status()
        seen.append((m.group(1), float(m.group(2)), int(m.group(7))))
        if m.group(1) == "Idle" and seen[-1][1] == 40.0:
            break
        time.sleep(0.02)
    runs = [s for s in seen if s[0] == "Run"]
    assert runs and all(0 <= x <= 40 for _, x, _ in runs) and {f for *_, f in runs} == {3000}
    assert len({x for _, x, _ in runs}) > 2  # the position moves between reports
    assert seen[-1] == ("Idle", 40.0, 0)


def test_feed_hold_and_resume(uno):
    port, chip = uno
    assert port.cmd("G1 X80 F3000") == ["ok"]
    port.wait_state("Run")
    time.sleep(0.3)
    port.write(b"!")
    states = [port.status().group(1)]
    held = port.wait_state("Hold:0", 5)
    assert held.group(1) == "Hold:0" and "Hold:1" in states + ["Hold:1"]
    x = float(held.group(2))
    assert 0 < x < 80
    time.sleep(0.4)
    assert port.status().group(1, 2) == ("Hold:0", held.group(2))  # nothing moves while held
    # a line sent while held waits, as in grbl with a full planner: the engine is still sampling
    # the held move into the stepper's queue; it is answered once the motion resumes
    port.write("G1 Y5\n")
    with pytest.raises(Exception):
        port.next_line(timeout=0.5)
    port.write(b"~")
    assert port.next_line() == "ok"
    done = port.wait_state("Idle", 10)
    assert done.group(2, 3) == ("80.000", "5.000")


def test_soft_reset_in_motion_alarms_and_unlocks(uno):
    port, _ = uno
    assert port.cmd("G1 X60 F3000") == ["ok"]
    port.wait_state("Run")
    port.write(b"\x18")
    lines = port.banner()
    assert "ALARM:3" in lines
    assert port.next_line() == "[MSG:'$H'|'$X' to unlock]"
    m = port.status()
    assert m.group(1) == "Alarm"
    x = float(m.group(2))
    assert 0 < x < 60  # stopped where it was, position kept
    assert port.cmd("G1 X1") == ["error:9"]  # G-code locked
    assert port.cmd("$X") == ["[MSG:Caution: Unlocked]", "ok"]
    assert port.status().group(1, 2) == ("Idle", m.group(2))
    assert port.cmd("G90 G0 X0") == ["ok"]
    assert port.wait_state("Idle").group(2) == "0.000"


def test_hold_then_reset_keeps_the_position_without_alarm(uno):
    port, _ = uno
    assert port.cmd("G1 X60 F3000") == ["ok"]
    port.wait_state("Run")
    time.sleep(0.2)
    port.write(b"!")
    held = port.wait_state("Hold:0", 5)
    port.write(b"\x18")
    lines = port.banner()
    assert not any(ln.startswith("ALARM") for ln in lines)
    assert port.status().group(1, 2) == ("Idle", held.group(2))


def test_dollar_commands(uno, grbl_firmware):
    port, _ = uno
    cfg = grbl_firmware[1]["machine"]
    settings = port.cmd("$$")
    assert settings[-1] == "ok"
    table = dict(ln[1:].split("=") for ln in settings[:-1])
    assert table["32"] == "1" and table["30"] == str(cfg.s_max)
    assert float(table["110"]) == cfg.max_feed_um_min / 1000 and float(table["120"]) == cfg.accel_um_s2[0] / 1000
    assert float(table["11"]) == cfg.junction_dev_um / 1000 and float(table["130"]) > 0
    assert port.cmd("G91 G20 M3 S300 F100") == ["ok"]
    assert port.cmd("$G") == ["[GC:G0 G54 G17 G20 G91 G94 M3 M9 T0 F2540 S300]", "ok"]
    assert port.cmd("$I") == ["[VER:1.1h.nnik:galvo_cba2012]", f"[OPT:V,{cfg.lookahead},128]", "ok"]
    assert port.cmd("$N") == ["$N0=", "$N1=", "ok"]
    assert port.cmd("$H") == ["error:5"]  # homing is not enabled
    assert port.cmd("$110=5000") == ["[MSG:nnik: settings are compiled in]", "error:3"]
    params = port.cmd("$#")
    assert params[0] == "[G54:0.000,0.000,0.000]" and params[-2] == "[PRB:0.000,0.000,0.000:0]"
    assert port.cmd("$X") == ["ok"]  # no alarm: nothing to do


def test_check_mode_parses_and_moves_nothing(uno):
    port, chip = uno
    assert port.cmd("$C") == ["[MSG:Enabled]", "ok"]
    assert port.status().group(1) == "Check"
    assert port.cmd("G1 X30 F3000") == ["ok"]
    assert port.cmd("G7") == ["error:20"]
    time.sleep(0.3)
    assert port.status().group(1, 2) == ("Check", "0.000")
    assert port.cmd("$C") == ["[MSG:Disabled]", "ok"]
    assert port.banner()[-1] == BANNER  # leaving check mode resets, as grbl
    assert port.status().group(1, 2) == ("Idle", "0.000")
    assert port.cmd("$G")[0].startswith("[GC:G0 G54 G17 G21 G90")  # the reset restored the modes


def test_m0_pauses_until_cycle_start(uno):
    port, _ = uno
    port.write("G1 X10 F3000\nM0\nG1 X20\n")
    assert port.next_line() == "ok"
    held = port.wait_state("Hold:0", 10)
    assert held.group(2) == "10.000"
    with pytest.raises(Exception):
        port.next_line(timeout=0.5)  # M0 is answered once the cycle starts again
    port.write(b"~")
    assert [port.next_line(), port.next_line()] == ["ok", "ok"]
    assert port.wait_state("Idle").group(2) == "20.000"


def test_character_counting_with_a_full_receive_buffer(uno):
    """128 bytes in flight, as grbl's stream.py streams: every line answered, in order."""
    port, _ = uno
    lines = [f"G1 X{(i % 10) * 3}.5 Y{i % 7}.25 F3000" for i in range(40)]
    inflight, sent, answers, fill_seen = [], 0, [], 0
    while len(answers) < len(lines):
        while sent < len(lines) and sum(inflight) + len(lines[sent]) + 1 <= 128:
            port.write(lines[sent] + "\n")
            inflight.append(len(lines[sent]) + 1)
            sent += 1
        fill_seen = max(fill_seen, sum(inflight))
        answers.append(port.next_line(timeout=20))
        inflight.pop(0)
    assert answers == ["ok"] * len(lines) and fill_seen > 120
    m = port.wait_state("Idle", 30)
    assert m.group(2, 3) == ("27.500", "4.250")
