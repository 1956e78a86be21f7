"""`nnik identify` as a user runs it (python3 -m nnik, a subprocess): the output's lines, the
scenario fragment and the picture on a good log; one `nnik: error:` line, exit 2 and no traceback
on each bad one."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT
from tests.dynamics.servo.synth_plant import excitation_log

K_X, TAU_X = 900.0, 0.04


def nnik(*args, cwd=None) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "nnik", *map(str, args)], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=300)


def log_text(volts, counts, tick=0.005, t=None, header="t,u_x,u_y,count_x,count_y") -> str:
    t = np.arange(len(volts)) * tick if t is None else t
    rows = [f"{t[i]:.6f},{volts[i, 0]:.6g},{volts[i, 1]:.6g},{counts[i, 0]:.0f},{counts[i, 1]:.0f}"
            for i in range(len(volts))]
    return "\n".join([header, *rows]) + "\n"


@pytest.fixture(scope="module")
def good():
    log = excitation_log(K_X, TAU_X, 6.0, 5.0, coulomb_v=0.3, stiction_v=0.4, noise_counts=0.5, seed=7, seconds=10)
    return log


def one_error(r: subprocess.CompletedProcess, *needles: str) -> str:
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("nnik: error: "), r.stderr
    assert "Traceback" not in r.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def test_a_good_log(tmp_path, good):
    src = tmp_path / "run1.csv"
    src.write_text(log_text(good.volts, good.counts + 40000))
    r = nnik("identify", src)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    for axis in "xy":
        mine = [ln for ln in lines if ln.startswith(f"{axis}:")]
        assert len(mine) == 1, lines
        m = re.fullmatch(rf"{axis}: K (\S+) counts/s/V, tau (\S+) s \(95 % CI (\S+) – (\S+) s; K (\S+) – (\S+) "
                         r"counts/s/V\)", mine[0])
        assert m, mine[0]
        k, tau, tlo, thi, klo, khi = map(float, m.groups())
        assert tlo < tau < thi and klo < k < khi
        assert abs(tau / TAU_X - 1) < 0.1 and abs(k / K_X - 1) < 0.25
    assert any("by RLS (the seed's method; batch LS agrees): P(z)/U(z) = " in ln for ln in lines)
    out = tmp_path / "run1.identified.toml"
    doc = tomllib.loads(out.read_text())
    assert set(doc["servo"]) == {"x", "y"}
    assert set(doc["servo"]["x"]["identified"]) == {"k_counts_s_v", "tau_s"}
    assert "[servo.x.identified]" in r.stdout
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_json_duty_log_and_cr_line_ends(tmp_path, good):
    """A duty log (--supply) with old-Mac CR line ends gives what the volts log gives."""
    volts_src, duty_src = tmp_path / "v.csv", tmp_path / "d.csv"
    volts_src.write_text(log_text(good.volts, good.counts))
    duty_src.write_bytes(log_text(good.volts / 12.0, good.counts).replace("\n", "\r").encode())
    a = nnik("identify", volts_src, "--json", "-o", tmp_path / "a.toml")
    b = nnik("identify", duty_src, "--supply", 12, "--json", "-o", tmp_path / "b.toml")
    assert a.returncode == 0 and b.returncode == 0, (a.stderr, b.stderr)
    ja, jb = json.loads(a.stdout), json.loads(b.stdout)
    assert jb["samples"] == ja["samples"] == len(good.t)
    for axis in "xy":
        assert jb["axes"][axis]["tau_s"] == pytest.approx(ja["axes"][axis]["tau_s"], rel=1e-6)


def test_counts8_unwraps_an_8bit_counter(tmp_path, good):
    raw = np.mod(good.counts + 100, 256)
    src = tmp_path / "c8.csv"
    src.write_text(log_text(good.volts, raw))
    one_error(nnik("identify", src), "8-bit counter", "--counts8")
    a = nnik("identify", src, "--counts8", "--json")
    full = tmp_path / "full.csv"
    full.write_text(log_text(good.volts, good.counts))
    b = nnik("identify", full, "--json")
    assert a.returncode == 0, a.stderr
    assert json.loads(a.stdout)["axes"]["x"]["tau_s"] == pytest.approx(json.loads(b.stdout)["axes"]["x"]["tau_s"])


def _bad(tmp_path, good, kind):
    v, c = good.volts.copy(), good.counts.copy()
    t = np.arange(len(v)) * 0.005
    if kind == "short":
        return log_text(v[:50], c[:50])
    if kind == "no excitation":
        v[:, 1] = 3.0
        return log_text(v, c)
    if kind == "still":
        c[:, 0] = 1234
        return log_text(v, c)
    if kind == "non-monotonic":
        t[500], t[501] = t[501], t[500]
        return log_text(v, c, t=t)
    if kind == "non-uniform":
        t[600:] += 0.002
        return log_text(v, c, t=t)
    if kind == "missing":
        return log_text(v, c, header="t,u_x,u_y,count_x,position_y")
    if kind == "nan":
        v[20, 0] = np.nan
        return log_text(v, c)
    if kind == "text":
        lines = log_text(v, c).splitlines()
        lines[40] = lines[40].replace(lines[40].split(",")[3], "12a", 1)
        return "\n".join(lines) + "\n"
    if kind == "empty":
        return ""
    raise AssertionError(kind)


BAD = [("short", ("too short", "50 samples")), ("no excitation", ("no excitation on y", "3 V at every sample")),
       ("still", ("count_x never changes",)), ("non-monotonic", ("time does not increase", "sample 502")),
       ("non-uniform", ("time step not uniform",)), ("missing", ("missing column count_y",)),
       ("nan", ("line 22", "u_x is nan, not a finite number")), ("text", ("line 41", "is not a number")), ("empty", ("empty file",))]


@pytest.mark.parametrize("kind,needles", BAD, ids=[b[0] for b in BAD])
def test_bad_logs(tmp_path, good, kind, needles):
    src = tmp_path / "bad.csv"
    src.write_text(_bad(tmp_path, good, kind))
    one_error(nnik("identify", src), str(src), *needles)
    assert not (tmp_path / "bad.identified.toml").exists()


def test_saturated_duty_the_whole_time(tmp_path, good):
    src = tmp_path / "sat.csv"
    duty = np.sign(good.volts)
    duty[duty == 0] = 1
    src.write_text(log_text(duty, good.counts))
    one_error(nnik("identify", src, "--supply", 12), "saturated", "every sample")


def test_duty_out_of_range_and_missing_file(tmp_path, good):
    src = tmp_path / "volts.csv"
    src.write_text(log_text(good.volts, good.counts))
    one_error(nnik("identify", src, "--supply", 12), "duty fractions in [-1, 1]")
    one_error(nnik("identify", tmp_path / "nope.csv"), "file not found")
    one_error(nnik("identify", src, "--supply", "-3"), "--supply")
    one_error(nnik("identify", src, "-o", tmp_path / "a.toml", "--png", tmp_path / "a.toml"), "the same file")


def test_never_writes_over_its_log(tmp_path, good):
    src = tmp_path / "log.csv"
    src.write_text(log_text(good.volts, good.counts))
    before = src.read_bytes()
    one_error(nnik("identify", src, "-o", src), "input")
    assert src.read_bytes() == before


def test_a_lag_under_half_a_tick_is_refused(tmp_path):
    """A motor whose speed follows the volts within the tick: the log cannot show its tau."""
    fast = excitation_log(900.0, 0.0008, 6.0, 400.0, noise_counts=0.5, seed=2, seconds=10)
    src = tmp_path / "fast.csv"
    src.write_text(log_text(fast.volts, fast.counts))
    one_error(nnik("identify", src), "under half a tick", "log at a shorter tick")
