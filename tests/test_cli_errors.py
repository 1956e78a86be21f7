"""Bad input: one clear line naming the file, key and problem, exit code 2, never a traceback."""

from __future__ import annotations

import subprocess
import sys

import pytest

from nnik.cli import main
from tests.conftest import DATASETS, write_toml

GOOD = (DATASETS / "galvo_cba2012.toml").read_text()


def _fails(capsys, path, *needles):
    rc = main(["generate", str(path), "-o", str(path.parent / "out")])
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("nnik: error: ")
    assert str(path) in lines[0]
    for n in needles:
        assert n in lines[0], lines[0]
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "old,new,needles",
    [
        ("z_mm = 300.0", "z_mm = 300.0\nzz_mm = 1.0", ["[mechanism] zz_mm", "unknown key"]),
        ("z_mm = 300.0", 'z_mm = "far"', ["[mechanism] z_mm", "expected a number"]),
        ("z_mm = 300.0", "z_mm = nan", ["[mechanism] z_mm", "finite"]),
        ("z_mm = 300.0", "", ["[mechanism] z_mm", "missing required key"]),
        ('kind = "galvo_gimbal"', 'kind = "scara"', ["[mechanism] kind", "must be one of"]),
        ("n_train = 1000", "n_train = 1000.5", ["[dataset] n_train", "expected an integer"]),
        ('sampling = "sobol"', 'sampling = "halton"', ["[dataset] sampling"]),
        ("hidden = [6]", "hidden = [6, 0]", ["[network] hidden"]),
        ('name = "galvo_cba2012"', 'name = "galvo-2012"', ["name", "C identifier"]),
        ("x_mm = [-100.0, 100.0]", "x_mm = [100.0, -100.0]", ["[workspace] x_mm", "min must be < max"]),
        ("x_mm = [-100.0, 100.0]", "x_mm = [-100.0, 100.0, 3.0]", ["[workspace] x_mm"]),
        ("steps_per_rev = 200", "steps_per_rev = 200\nbits = 16", ["[actuator] bits", "unknown key"]),
        ("[training]", "[trainig]", ["trainig", "unknown key"]),
    ],
)
def test_bad_scenario_values(tmp_path, capsys, old, new, needles):
    assert old in GOOD
    _fails(capsys, write_toml(tmp_path, GOOD.replace(old, new, 1)), *needles)


def test_malformed_toml(tmp_path, capsys):
    _fails(capsys, write_toml(tmp_path, GOOD.replace("z_mm = 300.0", "z_mm = = 300")), "malformed TOML")


def test_missing_file(tmp_path, capsys):
    _fails(capsys, tmp_path / "nope.toml", "not found")


def test_galvo_beyond_reach(tmp_path, capsys):
    bad = GOOD.replace("z_mm = 300.0", "z_mm = 300.0\nmax_mech_deg = 5.0")
    _fails(capsys, write_toml(tmp_path, bad), "[workspace]", "max_mech_deg", "swing")


def test_dac_range_exceeded(tmp_path, capsys):
    dual = (DATASETS / "galvo_dual_xy2.toml").read_text().replace("[-60.0, 60.0]", "[-90.0, 90.0]")
    _fails(capsys, write_toml(tmp_path, dual), "[workspace]", "DAC code")


def test_distortion_a_equals_b(tmp_path, capsys):
    text = (DATASETS / "corexy_nonlinear.toml").read_text()
    text = text.replace("A_deg = 90.25", "A_deg = 0.15")
    _fails(capsys, write_toml(tmp_path, text), "[mechanism.distortion]", "non-invertible")


def test_unknown_distortion_key(tmp_path, capsys):
    text = (DATASETS / "corexy_nonlinear.toml").read_text().replace("bow_mm", "bow_inch")
    _fails(capsys, write_toml(tmp_path, text), "[mechanism.distortion] bow_inch", "unknown key")


MEASURED = (DATASETS / "corexy_measured.toml").read_text()


@pytest.mark.parametrize(
    "csv,needles",
    [
        ("", ["empty CSV"]),
        ("x_um,y_um,q1\n1,2,3\n", ["header must be"]),
        ("x_um,y_um,q1,q2\n" + "1000,1000,1,2\n" * 30 + "1000,nan,1,2\n", ["line 32", "NaN"]),
        ("x_um,y_um,q1,q2\n" + "1000,1000,1,2\n" * 30 + "1000,abc,1,2\n", ["line 32", "not a number"]),
        ("x_um,y_um,q1,q2\n" + "1000,1000,1,2\n" * 30 + "1000,1000,1\n", ["line 32", "expected 4 values"]),
        ("x_um,y_um,q1,q2\n" + "1000,1000,1,2\n" * 5, ["only 5 data rows"]),
        ("x_um,y_um,q1,q2\n" + "1000,1000,1,2\n" * 30 + "900000,1000,1,2\n", ["outside [workspace]"]),
    ],
)
def test_bad_csv(tmp_path, capsys, csv, needles):
    (tmp_path / "corexy_measured.csv").write_text(csv)
    toml = write_toml(tmp_path, MEASURED)
    rc = main(["generate", str(toml), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1, err
    assert "corexy_measured.csv" in err
    for n in needles:
        assert n in err, err


def test_console_script_exit_code(tmp_path):
    """The real process: exit status 2 and no traceback."""
    bad = write_toml(tmp_path, GOOD.replace("z_mm = 300.0", "z_mm = -3.0"))
    r = subprocess.run([sys.executable, "-m", "nnik", "generate", str(bad)], capture_output=True, text=True)
    assert r.returncode == 2
    assert "[mechanism] z_mm: must be in (0, 100000] mm, got -3" in r.stderr
    assert "Traceback" not in r.stderr


def test_evaluate_missing_model(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path)]) == 2
    assert "model not found" in capsys.readouterr().err


def test_a_ctrl_c_that_a_library_turned_into_its_own_error_is_an_interrupt(capsys, monkeypatch, tmp_path):
    """numpy's zip writer answers a Ctrl-C in the middle of np.savez with a ValueError from its
    clean-up: the command still ends as interrupted (exit 130), without a traceback."""
    from nnik.commands import mlp_steps

    def save_interrupted(*a, **k):
        try:
            raise KeyboardInterrupt
        finally:
            raise ValueError("Can't close the ZIP file while there is an open writing handle on it.")

    monkeypatch.setattr(mlp_steps.pipeline, "generate", save_interrupted)
    rc = main(["generate", str(DATASETS / "galvo_cba2012.toml"), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 130, err
    assert err.strip() == "nnik: interrupted"


def test_an_error_without_an_interrupt_behind_it_is_not_hidden(monkeypatch, tmp_path):
    from nnik.commands import mlp_steps

    def broken(*a, **k):
        raise ValueError("a bug")

    monkeypatch.setattr(mlp_steps.pipeline, "generate", broken)
    with pytest.raises(ValueError, match="a bug"):
        main(["generate", str(DATASETS / "galvo_cba2012.toml"), "-o", str(tmp_path / "out")])
