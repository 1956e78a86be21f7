"""`nnik shaper-calibrate LOG.csv` from the command line: its first result line, the [shaper] lines a
scenario takes, the PNG, and every bad log as one `nnik: error:` line with exit 2."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from nnik.cli import main
from nnik.dynamics.resonance_test import raw_log, write_raw
from tests.machine.test_motion_tables import _load

DATA = Path(__file__).resolve().parents[1] / "data" / "resonance"
FIRST = re.compile(r"^resonance: (\d+\.\d) Hz, damping (\d\.\d{3})$")


@pytest.fixture(scope="module")
def raw(tmp_path_factory):
    """A raw log of a 48 Hz, zeta 0.1 axis (a shorter sweep than Klipper's: 20-90 Hz at 2 Hz/s)."""
    rows = raw_log(48.0, 0.1, seed=5, f_start=20.0, f_end=90.0, hz_per_sec=2.0)
    path = tmp_path_factory.mktemp("logs") / "raw_data_y_20261126_101010.csv"
    write_raw(path, rows)
    return path, rows


def test_a_raw_log_gives_the_resonance_first_and_the_shaper_lines(raw, tmp_path, capsys):
    path, _ = raw
    out = tmp_path / "shaper.toml"
    assert main(["shaper-calibrate", str(path), "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    m = FIRST.match(lines[0])
    assert m, lines[0]
    assert abs(float(m.group(1)) / 48.0 - 1) < 0.05 and abs(float(m.group(2)) / 0.1 - 1) < 0.2
    rec = next(ln for ln in lines if ln.startswith("recommended: "))
    assert re.match(r"recommended: (zv|mzv|ei|2hump_ei|3hump_ei) at \d+\.\d Hz \(vibration \d+\.\d %, smoothing "
                    r"\d\.\d{3} mm, max accel [\d,]+ mm/s\^2\)$", rec), rec
    for kind in ("zv", "mzv", "zvd", "ei", "2hump_ei", "3hump_ei"):
        assert any(ln.split()[:1] == [kind] for ln in lines), kind
    # the file is the printed [shaper] block; a scenario takes it as it is
    text = out.read_text()
    assert "[shaper]" in text and text.strip().splitlines() == lines[lines.index(text.splitlines()[0]):][:len(text.strip().splitlines())]
    scn = _load(tmp_path, text)
    assert scn.shaper["type"][0] == "none" and scn.shaper["type"][1] == rec.split()[1]  # the log tested Y
    assert scn.shaper["freq_hz"][1] == float(rec.split()[3])
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_the_shipped_processed_logs_and_the_axis_option(tmp_path, capsys):
    assert main(["shaper-calibrate", str(DATA / "resonances_x_synthetic.csv"), "--axis", "xy",
                 "--png", str(tmp_path / "p.png")]) == 0
    out = capsys.readouterr().out
    m = FIRST.match(out.splitlines()[0])
    assert m and abs(float(m.group(1)) / 38.5 - 1) < 0.05  # synthesised at 38.5 Hz, zeta 0.09 (README there)
    assert "shaper_type_x" in out and "shaper_type_y" in out and (tmp_path / "p.png").is_file()
    assert main(["shaper-calibrate", str(DATA / "resonances_y_synthetic.csv"), "--damping-ratio", "0.05"]) == 0
    out = capsys.readouterr().out
    assert abs(float(FIRST.match(out.splitlines()[0]).group(1)) / 52.0 - 1) < 0.05
    assert "damping_ratio_y = 0.05" in out and "shaper_type_x" not in out


def _bad(tmp_path, name: str, body) -> Path:
    p = tmp_path / name
    p.write_bytes(body if isinstance(body, bytes) else body.encode())
    return p


def _rows_text(rows) -> str:
    return "#time,accel_x,accel_y,accel_z\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows) + "\n"


def bad_logs(tmp_path, rows) -> dict:
    t = np.arange(0, 20, 1 / 3200)
    rng = np.random.default_rng(1)
    quiet = np.column_stack([t, rng.normal(0, 40, (len(t), 3))])
    clipped = rows.copy()
    top = 0.4 * np.abs(clipped[:, 2]).max()
    clipped[:, 2] = np.clip(clipped[:, 2], -top, top)
    back = rows[:5000].copy()
    back[2000, 0] = back[1999, 0]
    psd = (DATA / "resonances_x_synthetic.csv").read_text().splitlines()
    return {
        "empty": (_bad(tmp_path, "empty.csv", ""), "empty file"),
        "blank": (_bad(tmp_path, "blank.csv", "\n \n"), "empty file"),
        "binary": (_bad(tmp_path, "bin.csv", bytes(range(256)) * 4), "binary"),
        "latin1": (_bad(tmp_path, "l1.csv", "#time,accel_x,accel_y,accel_z\n1.0,\xe9\n".encode("latin-1")), "not text"),
        "header": (_bad(tmp_path, "h.csv", "#time,ax,ay,az\n0,1,2,3\n"), "expected Klipper's raw accelerometer header"),
        "columns": (_bad(tmp_path, "c.csv", _rows_text(rows[:100]) + "5.0,1.0,2.0\n"), "3 columns, expected 4"),
        "text": (_bad(tmp_path, "t.csv", _rows_text(rows[:100]).replace("\n1", "\nabc", 1)), "is not a number"),
        "nan": (_bad(tmp_path, "n.csv", _rows_text(rows[:100]) + "9999.0,nan,1,2\n"), "not finite"),
        "short": (_bad(tmp_path, "s.csv", _rows_text(rows[:3200])), "too short"),
        "backwards": (_bad(tmp_path, "b.csv", _rows_text(back)), "time does not increase"),
        "clipped": (_bad(tmp_path, "clip.csv", _rows_text(clipped)), "accel_y is clipped"),
        "no resonance": (_bad(tmp_path, "q.csv", _rows_text(quiet)), "no resonance in"),
        "psd short": (_bad(tmp_path, "ps.csv", "\n".join(psd[:8]) + "\n"), "too short"),
        "psd negative": (_bad(tmp_path, "pn.csv", "\n".join(psd[:40] + [psd[40].replace(",", ",-", 1)] + psd[41:]) + "\n"),
                         "negative"),
        "psd columns": (_bad(tmp_path, "pc.csv", "\n".join(psd[:40] + ["50.0,1e3,2e3"] + psd[41:]) + "\n"), "columns"),
        "missing": (tmp_path / "nope.csv", "file not found"),
        "directory": (tmp_path, "a directory, not a resonance test log"),
    }


def test_bad_logs_are_one_line_and_exit_2(raw, tmp_path, capsys):
    _, rows = raw
    for what, (path, msg) in bad_logs(tmp_path, rows).items():
        assert main(["shaper-calibrate", str(path)]) == 2, what
        cap = capsys.readouterr()
        err = cap.err.strip()
        assert err.startswith(f"nnik: error: {path}: ") and "\n" not in err and msg in err, (what, err)
        assert not cap.out, (what, cap.out)  # nothing printed before the error


def test_bad_options_are_one_line(raw, tmp_path, capsys):
    path, _ = raw
    for args, msg in ((["--damping-ratio", "0.5"], "--damping-ratio"), (["--damping-ratio", "x"], "--damping-ratio"),
                      (["-o", str(tmp_path / "no" / "s.toml")], "no such directory"), (["--png", str(tmp_path)], "a directory")):
        assert main(["shaper-calibrate", str(path), *args]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("nnik: error: ") and "\n" not in err and msg in err, err
    z = tmp_path / "raw_data_z_1.csv"
    z.write_bytes(path.read_bytes())
    assert main(["shaper-calibrate", str(z)]) == 2
    assert "nnik shapes X and Y" in capsys.readouterr().err
