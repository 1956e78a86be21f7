"""Measured CSVs that crashed or passed silently (issue 11, sections 3-4): one line and exit 2,
or (a UTF-8 BOM, duplicate rows) accepted with the right meaning."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.cli import main
from nnik.machine.data import Dataset
from tests.bad_input import MEASURED, fails
from tests.conftest import DATASETS, write_toml

CSV = (DATASETS / "corexy_measured.csv").read_text()
HEADER = "x_um,y_um,q1,q2\n"


def _setup(tmp_path, csv_bytes: bytes, toml: str = MEASURED):
    (tmp_path / "corexy_measured.csv").write_bytes(csv_bytes)
    return write_toml(tmp_path, toml), tmp_path / "out"


def _csv_fails(tmp_path, capsys, csv_bytes, *needles, toml=MEASURED):
    scn, out = _setup(tmp_path, csv_bytes, toml)
    fails(capsys, ["generate", scn, "-o", out], "corexy_measured.csv", *needles, watch=out)
    assert not out.exists()


def _grid_rows(n: int, lo=(0.0, 0.0), hi=(200.0, 200.0), seed=0) -> str:
    rng = np.random.default_rng(seed)
    p = rng.uniform(lo, hi, (n, 2)) * 1000
    return "".join(f"{x:.1f},{y:.1f},{int(x / 10)},{int(y / 10)}\n" for x, y in p)


def test_latin1_byte(tmp_path, capsys):
    data = CSV.encode() + "caf\u00e9,1,2,3\n".encode("latin-1")
    _csv_fails(tmp_path, capsys, data, "not UTF-8", "0xe9", "line 602")


def test_huge_field(tmp_path, capsys):
    data = (CSV + "1" * 200_000 + ",1,2,3\n").encode()
    _csv_fails(tmp_path, capsys, data, "line 602", "field larger than field limit")


def test_unterminated_quote(tmp_path, capsys):
    data = (CSV + '"1000,1,2,3\n' + "x" * 140_000).encode()
    _csv_fails(tmp_path, capsys, data, "line 602")


def test_utf8_bom_is_accepted(tmp_path, capsys):
    scn, out = _setup(tmp_path, b"\xef\xbb\xbf" + CSV.encode())
    assert main(["generate", str(scn), "-o", str(out)]) == 0, capsys.readouterr().err
    ds = Dataset.load(out / "data.npz")
    assert sum(len(v) for v in ds.p.values()) == 600


def test_bad_header_names_hidden_characters(tmp_path, capsys):
    _csv_fails(tmp_path, capsys, ("x_um\u200b,y_um,q1,q2\n" + CSV.split("\n", 1)[1]).encode(), "header must be",
               "\\u200b")


def test_identical_rows(tmp_path, capsys):
    _csv_fails(tmp_path, capsys, (HEADER + "100000,100000,1,2\n" * 600).encode(), "only 1 distinct positions in 600 rows")


def test_rows_in_one_corner(tmp_path, capsys):
    _csv_fails(tmp_path, capsys, (HEADER + _grid_rows(400, hi=(45.0, 45.0))).encode(),
               "do not cover [workspace]", "15 of 16 cells")


def test_rows_on_one_line(tmp_path, capsys):
    rows = "".join(f"{x * 1000:.1f},{x * 1000:.1f},{int(x)},{int(x)}\n" for x in np.linspace(1, 199, 300))
    _csv_fails(tmp_path, capsys, (HEADER + rows).encode(), "do not cover [workspace]")


def test_dac_codes_beyond_range(tmp_path, capsys):
    dac = MEASURED.replace('kind = "stepper"\nsteps_per_rev = 200\nmicrosteps = 16\nmm_per_rev = 40.0',
                           'kind = "dac"\nbits = 12')
    assert 'kind = "dac"' in dac
    rows = _grid_rows(300).replace(",", " ").split("\n")
    body = "".join(f"{r.split()[0]},{r.split()[1]},{int(float(r.split()[0]) / 10)},0\n" for r in rows if r)
    _csv_fails(tmp_path, capsys, (HEADER + body).encode(), "q1/q2 columns", "DAC code", "12-bit", toml=dac)


def test_duplicate_rows_do_not_leak_into_the_held_out_set(tmp_path, capsys):
    """300 rows, each twice: merged before splitting, so no test position is also trained on."""
    rows = _grid_rows(300, seed=3)
    scn, out = _setup(tmp_path, (HEADER + rows + rows).encode())
    assert main(["generate", str(scn), "-o", str(out)]) == 0, capsys.readouterr().err
    ds = Dataset.load(out / "data.npz")
    assert sum(len(v) for v in ds.p.values()) == 300
    assert ds.meta["duplicates_merged"] == 300
    train = {tuple(r) for r in np.concatenate([ds.p["train"], ds.p["val"]])}
    assert not any(tuple(r) in train for r in ds.p["test"])


@pytest.mark.parametrize("order", ["first", "last"])
def test_duplicate_positions_average_their_commands(tmp_path, capsys, order):
    rows = _grid_rows(300, seed=4).splitlines()
    x, y, q1, q2 = rows[0].split(",")
    extra = f"{x},{y},{int(q1) + 2},{int(q2) - 2}"
    body = [extra] + rows if order == "first" else rows + [extra]
    scn, out = _setup(tmp_path, (HEADER + "\n".join(body) + "\n").encode())
    assert main(["generate", str(scn), "-o", str(out)]) == 0
    ds = Dataset.load(out / "data.npz")
    p = np.concatenate(list(ds.p.values()))
    q = np.concatenate(list(ds.q.values()))
    i = np.flatnonzero(np.all(p == [float(x) / 1000, float(y) / 1000], axis=1))
    assert len(i) == 1
    assert np.allclose(q[i[0]], [int(q1) + 1, int(q2) - 1])
