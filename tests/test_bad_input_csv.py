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
    body = "".join(f"{r.split()[0]},{r.split()[1]},{int(float(r.split()[0]) / 10)},{int(float(r.split()[1]) / 100)}\n"
                   for r in rows if r)  # q2 within 12 bits, q1 beyond
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


# ---- data that lies (issue 25): copies warned about and kept out of the noise estimate; readings that
# cannot be a machine, and too few marks for the network, refused at the input
NO_NOISE = MEASURED.replace("noise_um = 2.0", "")
MARKS = [r for r in CSV.splitlines()[1:] if r]


def _generate_warns(tmp_path, capsys, csv_text: str, *needles: str, toml: str = NO_NOISE):
    scn, out = _setup(tmp_path, csv_text.encode(), toml)
    capsys.readouterr()
    assert main(["generate", str(scn), "-o", str(out)]) == 0
    warns = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("nnik: warning:")]
    assert len(warns) == 1, warns
    for n in needles:
        assert n in warns[0], (n, warns[0])
    return scn, out


def test_every_row_written_twice_is_not_a_perfect_instrument(tmp_path, capsys):
    """The issue's case: 600 marks, each written twice with identical readings, read as noise
    floor 0 (the copies' spread); the copies are counted once and say nothing about the noise."""
    from nnik.machine.reference import repeated_noise
    from nnik.machine.scenario import load_scenario

    body = "".join(r + "\n" + r + "\n" for r in MARKS)
    scn, out = _generate_warns(tmp_path, capsys, HEADER + body, "600 of 1200 rows repeat an earlier row exactly",
                               "left out of the noise estimate")
    m = load_scenario(scn).mechanism
    assert m.copies == 600 and len(m.positions_mm) == 600
    assert repeated_noise(*m.rows) is None  # no repeats left to measure a spread from
    assert Dataset.load(out / "data.npz").meta["copies"] == 600


def test_copies_do_not_dilute_the_spread_of_true_repeats(tmp_path, capsys):
    """100 marks read again with readings that differ by one step, and every row then copied:
    the noise is the true repeats' spread (variance 1/2 per pair), not diluted by the copies."""
    from nnik.machine.reference import repeated_noise
    from nnik.machine.scenario import load_scenario

    rng = np.random.default_rng(11)
    again = []
    for r in MARKS[:100]:
        x, y, q1, q2 = r.split(",")
        d1, d2 = rng.choice([-1, 1], 2)
        again.append(f"{x},{y},{int(q1) + d1},{int(q2) + d2}")
    rows = MARKS + again
    order = rng.permutation(2 * len(rows))
    doubled = [rows[i % len(rows)] for i in order]
    scn, _ = _generate_warns(tmp_path, capsys, HEADER + "\n".join(doubled) + "\n", "700 of 1400 rows")
    m = load_scenario(scn).mechanism
    noise = repeated_noise(*m.rows)
    assert np.allclose(noise.variance, 0.5) and "100 repeated marks" in noise.source


def test_constant_readings_are_refused_before_any_compiler(tmp_path, capsys):
    """issue 25: readings all the same failed inside the C compiler; now `nnik run` refuses the CSV."""
    body = "".join(f"{r.rsplit(',', 2)[0]},1200,-340\n" for r in MARKS)
    scn, out = _setup(tmp_path, (HEADER + body).encode())
    fails(capsys, ["run", scn, "-o", out], "corexy_measured.csv", "q1 is 1200 on every row", watch=out)
    assert not out.exists()


def test_one_constant_column_is_refused(tmp_path, capsys):
    body = "".join(f"{r.rsplit(',', 1)[0]},7\n" for r in MARKS)
    _csv_fails(tmp_path, capsys, (HEADER + body).encode(), "q2 is 7 on every row")


def test_readings_that_do_not_follow_the_position_are_refused(tmp_path, capsys):
    """The readings' column shuffled against the positions (rows from different marks)."""
    rng = np.random.default_rng(5)
    q = [r.split(",", 2)[2] for r in MARKS]
    body = "".join(f"{r.split(',')[0]},{r.split(',')[1]},{q[i]}\n" for r, i in zip(MARKS, rng.permutation(len(q))))
    _csv_fails(tmp_path, capsys, (HEADER + body).encode(), "q1 does not follow the position", "% of its variance")


def test_two_columns_that_move_as_one_are_refused(tmp_path, capsys):
    body = "".join(f"{r.rsplit(',', 1)[0]},{r.split(',')[2]}\n" for r in MARKS)
    _csv_fails(tmp_path, capsys, (HEADER + body).encode(), "q1 and q2 move together")


def test_too_few_marks_for_the_network_are_refused(tmp_path, capsys):
    """60 marks leave 36 training rows (72 readings); a 2-16-2 network has 82 weights."""
    toml = MEASURED.replace("hidden = [8]", "hidden = [16]")
    scn, out = _setup(tmp_path, (HEADER + "\n".join(MARKS[:60]) + "\n").encode(), toml)
    fails(capsys, ["run", scn, "-o", out], "s.toml: [network] hidden", "hidden [16] has 82 weights", "72 readings",
          "measure at least 68 marks", watch=out)
    assert not out.exists()


def test_enough_marks_for_the_network_pass(tmp_path, capsys):
    """68 marks: 41 training rows, 82 readings for 82 weights."""
    toml = MEASURED.replace("hidden = [8]", "hidden = [16]")
    scn, out = _setup(tmp_path, (HEADER + "\n".join(MARKS[:68]) + "\n").encode(), toml)
    assert main(["generate", str(scn), "-o", str(out)]) == 0, capsys.readouterr().err


def test_a_directory_where_the_csv_should_be(tmp_path, capsys):
    (tmp_path / "corexy_measured.csv").mkdir()
    scn, out = write_toml(tmp_path, MEASURED), tmp_path / "out"
    fails(capsys, ["generate", scn, "-o", out], "corexy_measured.csv", "a directory, not a CSV of measured marks",
          watch=out)
    assert not out.exists()
