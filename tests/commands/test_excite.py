"""`nnik excite` on the shipped DC-servo scenario (python3 -m nnik, a subprocess): its files agree
with each other, the table stays in its strokes, `nnik identify` reads the log back to the
plant's own K and tau, the duty header builds for the Uno with avr-gcc, and bad input is one line."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

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
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    one_error(nnik("excite", XY, "-o", mine, "--seconds", 2), "not written by nnik")
    assert (mine / "notes.txt").read_text() == "keep"
