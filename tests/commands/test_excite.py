"""`nnik excite` on the shipped DC-servo scenario (python3 -m nnik, a subprocess): its files agree
with each other, the table stays in its strokes, `nnik identify` reads the log back to the
plant's own K and tau, the duty header builds for the Uno with avr-gcc, the firmware build
(arduino-mk) fits the Uno and, on simavr in closed loop with the plant, prints the Python log's
serial text byte for byte, which identify reads to the same K and tau; bad input is one line."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.dynamics.servo.nominal import equivalent_tau_s, nominal_model
from nnik.machine.scenario import load_scenario
from tests.commands.test_identify import nnik, one_error
from tests.conftest import DATASETS

XY = DATASETS / "xy_table.toml"


@pytest.fixture(scope="module")
def excited(tmp_path_factory):
    out = tmp_path_factory.mktemp("excite") / "ex"
    r = nnik("excite", XY, "-o", out, "--seconds", 10, "--seed", 3)
    assert r.returncode == 0, r.stderr
    return out, r.stdout


def test_files_agree_and_stay_in_the_strokes(excited):
    out, stdout = excited
    cfg = load_scenario(XY).servo
    duty = np.loadtxt(out / "duty.csv", delimiter=",", skiprows=1)
    log = np.loadtxt(out / "log.csv", delimiter=",", skiprows=1)
    assert len(duty) == len(log) == 2000
    assert np.allclose(duty[:, 0], log[:, 0]) and np.allclose(np.diff(log[:, 0]), cfg.tick_s)
    assert np.allclose(duty[:, 1:] / cfg.duty_max * cfg.supply_v, log[:, 1:3], rtol=1e-5)
    assert (duty[:, 1:] == np.rint(duty[:, 1:])).all() and np.abs(duty[:, 1:]).max() <= cfg.duty_max
    assert not (duty[:, 1] == duty[:, 2]).all()
    um = cfg.um_per_count
    for i, (lo, hi) in enumerate(((0, 200), (0, 150))):
        mm = log[:, 3 + i] * um / 1000
        assert lo < mm.min() and mm.max() < hi
        assert abs(mm[0] - (lo + hi) / 2) < 0.01  # starts centred
    for m in re.finditer(r"square \+-(\S+) V, .* noise sigma (\S+) V", stdout):
        assert float(m.group(2)) ** 2 == pytest.approx(0.3 * float(m.group(1)), rel=0.01)


def test_same_seed_same_files(excited, tmp_path):
    out, _ = excited
    r = nnik("excite", XY, "-o", tmp_path / "again", "--seconds", 10, "--seed", 3)
    assert r.returncode == 0, r.stderr
    for name in ("duty.csv", "log.csv", "nnik_excite_duties.h"):
        assert (tmp_path / "again" / name).read_bytes() == (out / name).read_bytes()


def test_identify_reads_the_log_back_to_the_plant(excited, tmp_path):
    out, _ = excited
    r = nnik("identify", out / "log.csv", "-o", tmp_path / "id.toml", "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)["axes"]
    cfg = load_scenario(XY).servo
    for i, axis in enumerate("xy"):
        assert got[axis]["tau_s"] == pytest.approx(equivalent_tau_s(cfg, i), rel=0.05)
        assert got[axis]["k_counts_s_v"] == pytest.approx(nominal_model(cfg, i).k_counts_s_v, rel=0.05)


@pytest.mark.skipif(shutil.which("avr-gcc") is None, reason="avr-gcc not installed")
def test_the_duty_table_builds_for_the_uno(excited, tmp_path):
    out, _ = excited
    src = tmp_path / "t.c"
    src.write_text('#include "nnik_excite_duties.h"\nint16_t nnik_excite_duty(uint16_t k, uint8_t a) '
                   '{ return (int16_t)pgm_read_word(&nnik_excite_duties[k][a]); }\n')
    obj = tmp_path / "t.o"
    subprocess.run(["avr-gcc", "-mmcu=atmega328p", "-Os", "-Wall", "-Werror", "-I", str(out), "-c", str(src), "-o",
                    str(obj)], check=True)
    sym = subprocess.run(["avr-nm", "-S", str(obj)], capture_output=True, text=True, check=True).stdout
    size = next(int(ln.split()[1], 16) for ln in sym.splitlines() if ln.endswith(" nnik_excite_duties"))
    assert size == 2000 * 2 * 2
    raw = tmp_path / "table.bin"  # the flash image of the table: the duties of duty.csv, row by row
    subprocess.run(["avr-objcopy", "-O", "binary", "-j", ".progmem.data", str(obj), str(raw)], check=True)
    table = np.frombuffer(raw.read_bytes(), dtype="<i2").reshape(-1, 2)
    duty = np.loadtxt(out / "duty.csv", delimiter=",", skiprows=1)[:, 1:]
    assert (table == duty).all()


def test_bad_input(tmp_path):
    one_error(nnik("excite", DATASETS / "galvo_cba2012.toml", "-o", tmp_path / "g"), "no [servo] table")
    one_error(nnik("excite", XY, "-o", tmp_path / "long", "--seconds", 40), "--seconds", "24576 bytes")
    one_error(nnik("excite", XY, "--seconds", 0.1), "--seconds")
    text = XY.read_text()
    assert "tick_s = 0.005 " in text
    for tick, what in (("0.0050005", "whole microseconds"), ("0.002", "115200 baud")):
        odd = tmp_path / f"odd_{what[:5]}.toml"
        odd.write_text(text.replace("tick_s = 0.005 ", f"tick_s = {tick} "))
        one_error(nnik("excite", odd, "-o", tmp_path / "odd", "--seconds", 2), what)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    one_error(nnik("excite", XY, "-o", mine, "--seconds", 2), "not written by nnik")
    assert (mine / "notes.txt").read_text() == "keep"


def test_the_serial_format_is_identifys(tmp_path):
    """Every duty's printed fraction reads back to that duty; identify's reader takes the log with
    --supply as the duties in volts."""
    from nnik.dynamics.servo.log_csv import read_servo_log
    from nnik.firmware.servo.excite_export import serial_log

    cfg = load_scenario(XY).servo
    d = np.arange(-cfg.duty_max, cfg.duty_max + 1)
    duty = np.stack([d, d[::-1]], 1)
    counts = np.stack([np.arange(len(d)) * 7 - 40, -np.arange(len(d)) * 3], 1)
    text = serial_log(duty, counts, cfg.tick_s, cfg.duty_max)
    (tmp_path / "log.csv").write_text(text)
    log = read_servo_log(tmp_path / "log.csv", supply_v=cfg.supply_v)
    assert (np.rint(log.duty * cfg.duty_max) == duty).all() and np.abs(log.duty * cfg.duty_max - duty).max() < 1e-3
    assert np.allclose(log.volts, duty / cfg.duty_max * cfg.supply_v, atol=1e-5) and (log.counts == counts).all()
    assert np.allclose(log.t, np.arange(len(d)) * cfg.tick_s, atol=1e-9)
    assert text.splitlines()[-1].startswith("# end:")


def _need_arduino_mk():
    if not os.path.isfile("/usr/share/arduino/Arduino.mk") or shutil.which("make") is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("arduino-mk not installed")
        pytest.skip("arduino-mk not installed (run scripts/install_toolchains.sh)")


def test_the_firmware_builds_fits_and_logs_the_plant_on_the_chip(excited, tmp_path):
    """The arduino-mk sketch on simavr, closed loop with the scenario's plant (its encoder edges):
    the UART's bytes = the Python log's text (the table's duty, the plant's counts) line for line,
    every tick; the motors stop at the end; identify reads the chip's log as the Python log."""
    from nnik.firmware.servo.build import FLASH_BYTES, RAM_BYTES, sketch_firmware
    from nnik.firmware.servo.cosim import run
    from nnik.firmware.servo.excite_export import TablePlayer, serial_log
    from nnik.commands.excite import MAX_TABLE_BYTES

    _need_arduino_mk()
    out, _ = excited
    cfg = load_scenario(XY).servo
    ex = out / "nnik_xy_table_excite" / "examples" / "xy_table_excite"
    r = subprocess.run(["make", "-s"], cwd=ex, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-800:]
    fw = sketch_firmware(next((ex / "build-uno").glob("*.elf")), cfg.tick_s)
    table = 2000 * 4
    assert fw.flash_bytes > table and fw.ram_bytes <= RAM_BYTES
    assert fw.flash_bytes - table + MAX_TABLE_BYTES <= FLASH_BYTES  # the longest table --seconds allows fits too
    if shutil.which("simavr") is None:
        pytest.skip("simavr not installed")
    duty = np.loadtxt(out / "duty.csv", delimiter=",", skiprows=1)[:, 1:].astype(np.int64)
    log = np.loadtxt(out / "log.csv", delimiter=",", skiprows=1)
    counts = log[:, 3:].astype(np.int64)
    uart = tmp_path / "serial.csv"
    tr = run(fw, cfg, TablePlayer(duty), np.zeros((len(duty) + 3, 2), np.int64), tmp_path / "run",
             start_counts=tuple(counts[0]), uart_log=uart)
    assert tr.mismatches == 0 and tr.lost_counts == 0
    assert (tr.counts[:len(duty)] == counts).all()  # the chip's plant is the Python log's
    assert (tr.chip_duty[len(duty):] == 0).all()  # stopped
    got, want = uart.read_text().splitlines(), serial_log(duty, counts, cfg.tick_s, cfg.duty_max).splitlines()
    assert len(got) == len(want) == len(duty) + 2
    bad = [k for k, (a, b) in enumerate(zip(got, want)) if a != b]
    assert not bad, f"line {bad[0] + 1}: chip {got[bad[0]]!r}, Python {want[bad[0]]!r}"
    ids = []
    for args in ((uart, "--supply", cfg.supply_v), (out / "log.csv",)):
        r = nnik("identify", *args, "-o", tmp_path / f"id{len(ids)}.toml", "--json")
        assert r.returncode == 0, r.stderr
        ids.append(json.loads(r.stdout)["axes"])
    for i, axis in enumerate("xy"):
        for key in ("k_counts_s_v", "tau_s"):
            assert ids[0][axis][key] == pytest.approx(ids[1][axis][key], rel=1e-4)
        assert ids[0][axis]["tau_s"] == pytest.approx(equivalent_tau_s(cfg, i), rel=0.05)
        assert ids[0][axis]["k_counts_s_v"] == pytest.approx(nominal_model(cfg, i).k_counts_s_v, rel=0.05)


@st.composite
def tables(draw):
    n = draw(st.integers(1, 40))
    duty = draw(st.lists(st.tuples(st.integers(-255, 255), st.integers(-255, 255)), min_size=n, max_size=n))
    counts = draw(st.lists(st.tuples(st.integers(-2**31, 2**31 - 1), st.integers(-2**31, 2**31 - 1)), min_size=n,
                           max_size=n))
    return np.array(duty), np.array(counts), draw(st.integers(1, 32768)), draw(st.sampled_from([255, 1023, 100]))


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")
@settings(max_examples=8, deadline=None)
@given(t=tables())
def test_the_players_lines_are_serial_logs(t, tmp_path_factory):
    """nnik_ctl_excite.c on the host (the same C the Uno runs): each tick's line = serial_log's,
    any duty and int32 count, any whole-microsecond tick; after the table, duty 0 and no line."""
    from nnik.emit.templating import CODEGEN
    from nnik.firmware.servo.excite_export import serial_log

    duty, counts, us, duty_max = t
    tmp = tmp_path_factory.mktemp("player")
    rows = ",".join("{%d,%d}" % tuple(d) for d in duty.tolist())
    (tmp / "nnik_excite_duties.h").write_text(
        f"#include <stdint.h>\n#define NNIK_EXCITE_TICKS {len(duty)}\n#define NNIK_EXCITE_TICK_US {us}UL\n"
        f"#define NNIK_DUTY_MAX {duty_max}\nstatic const int16_t nnik_excite_duties[][2] = {{{rows}}};\n")
    pos = ",".join("{%dL,%dL}" % tuple(c) for c in counts.tolist())
    (tmp / "main.c").write_text(f"""#include <stdio.h>
#include "nnik_ctl.h"
#include "nnik_excite.h"
static const int32_t pos[][2] = {{{pos}}};
int main(void) {{
    char buf[NNIK_EXCITE_LINE_MAX]; int32_t ref[2] = {{0, 0}}; int16_t d[2]; unsigned k;
    nnik_ctl_reset();
    for (k = 0; k < {len(duty) + 2}; k++) {{
        nnik_ctl_tick(ref, pos[k < {len(duty)} ? k : 0], d);
        if (k >= {len(duty)} && (d[0] || d[1])) return 3;
        while (nnik_excite_line(buf)) fputs(buf, stdout);
    }}
    printf("done %u lost %u\\n", nnik_excite_done(), nnik_excite_lost());
    return 0;
}}
""")
    src = CODEGEN / "arduino" / "src"
    exe = tmp / "player"
    subprocess.run(["gcc", "-std=gnu11", "-Wall", "-Werror", "-I", str(tmp), "-I", str(src), str(src / "nnik_ctl_excite.c"),
                    str(tmp / "main.c"), "-o", str(exe)], check=True)
    got = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.splitlines()
    want = serial_log(duty, counts, us * 1e-6, duty_max).splitlines()[1:-1]
    assert got[:-1] == want and got[-1] == "done 1 lost 0"
