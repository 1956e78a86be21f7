"""[motion] and [dynamics]: defaults, and every bad value as one line naming the key."""

import re
import shutil
from pathlib import Path

import pytest

from nnik.errors import NnikError
from nnik.machine.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
BASE = (ROOT / "datasets" / "galvo_cba2012.toml").read_text()


def _load(tmp_path, extra: str):
    p = tmp_path / "s.toml"
    p.write_text(BASE + "\n" + extra)
    return load_scenario(p)


def test_defaults_without_tables(tmp_path):
    s = _load(tmp_path, "")
    assert s.dynamics is None
    assert s.motion["shaper"] == "none" and s.motion["sample_hz"] == 1000
    assert s.motion["junction_deviation_mm"] == 0.01 and s.motion["accel_x_mm_s2"] > 0


def test_shipped_corexy_has_the_goals_machine():
    s = load_scenario(ROOT / "datasets" / "corexy_nonlinear.toml")
    assert s.dynamics == {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)}
    assert s.motion["accel_x_mm_s2"] == s.motion["accel_y_mm_s2"] == 3000.0


def test_per_axis_pairs_and_the_fingerprint_ignores_motion(tmp_path):
    a = _load(tmp_path, "[dynamics]\nf_hz = [40, 52.5]\nzeta = [0.1, 0.05]\n")
    assert a.dynamics == {"f_hz": (40.0, 52.5), "zeta": (0.1, 0.05)}
    b = _load(tmp_path, "")
    assert a.fingerprint == b.fingerprint  # no new data or model for a new belt


@pytest.mark.parametrize("extra, key", [
    ("[motion]\naccel_x_mm_s2 = -5\n", "[motion] accel_x_mm_s2"),
    ("[motion]\naccel_y_mm_s2 = nan\n", "[motion] accel_y_mm_s2"),
    ("[motion]\nsample_hz = 3000\n", "[motion] sample_hz"),
    ("[motion]\nshaper = \"zvdd\"\n", "[motion] shaper"),
    ("[motion]\nshaper = \"zvd\"\n", "[motion] shaper"),  # no [dynamics]
    ("[motion]\njerk = 5\n", "[motion] jerk"),
    ("[motion]\nmax_feed_mm_min = 0\n", "[motion] max_feed_mm_min"),
    ("[dynamics]\nf_hz = 40\n", "[dynamics] zeta"),
    ("[dynamics]\nf_hz = 400\nzeta = 0.1\n", "[dynamics] f_hz"),  # above a quarter of 1 kHz
    ("[dynamics]\nf_hz = [40, 0.5]\nzeta = 0.1\n", "[dynamics] f_hz"),
    ("[dynamics]\nf_hz = [40, 40, 40]\nzeta = 0.1\n", "[dynamics] f_hz"),
    ("[dynamics]\nf_hz = 40\nzeta = -0.1\n", "[dynamics] zeta"),
    ("[dynamics]\nf_hz = 40\nzeta = \"low\"\n", "[dynamics] zeta"),
    ("[motion]\nshaper = \"ei\"\n[dynamics]\nf_hz = 40\nzeta = 1.0\n", "[dynamics] zeta"),  # overdamped
    ("[dynamics]\nf_hz = 40\nzeta = 0.1\nmass = 2\n", "[dynamics] mass"),
])
def test_bad_values_are_one_line_naming_the_key(tmp_path, extra, key):
    with pytest.raises(NnikError) as exc:
        _load(tmp_path, extra)
    msg = str(exc.value)
    assert key in msg and "\n" not in msg


def test_overdamped_axis_is_fine_without_a_shaper(tmp_path):
    s = _load(tmp_path, "[dynamics]\nf_hz = 40\nzeta = 1.0\n")
    assert s.dynamics["zeta"] == (1.0, 1.0)
