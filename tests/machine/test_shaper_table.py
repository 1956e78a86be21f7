"""[shaper]: the input shaper per axis with Klipper's [input_shaper] keys, its defaults, the older
[motion] shaper + [dynamics] form mapped onto the same taps, and every bad value as one line."""

import pytest

from nnik.dynamics.shapers import design, quantize
from nnik.errors import NnikError
from nnik.firmware.config import default_machine
from tests.machine.test_motion_tables import _load


def test_per_axis_types_frequencies_and_damping(tmp_path):
    s = _load(tmp_path, '[shaper]\nshaper_type_x = "MZV"\nshaper_freq_x = 42.6\nshaper_type_y = "3hump_ei"\n'
                        'shaper_freq_y = 61.0\ndamping_ratio_y = 0.15\n')
    assert s.shaper == {"type": ("mzv", "3hump_ei"), "freq_hz": (42.6, 61.0), "damping": (0.1, 0.15),
                        "label": "mzv/3hump_ei"}
    assert s.motion["shaper"] == "mzv/3hump_ei"
    cfg = default_machine(s)
    assert cfg.shaper == "mzv/3hump_ei"
    want = [quantize(design("mzv", 42.6, 0.1), 1000), quantize(design("3hump_ei", 61.0, 0.15), 1000)]
    assert [tuple(map(list, t)) for t in cfg.shaper_taps] == [tuple(w) for w in want]
    assert cfg.shaper_design == (("mzv", 42.6, 0.1), ("3hump_ei", 61.0, 0.15))
    assert len(cfg.shaper_taps[1][0]) <= 10 and cfg.defines()["NNIK_SH_N"] == str(max(len(a) for a, _ in cfg.shaper_taps))


def test_klippers_defaults_shaper_type_mzv_and_an_axis_without_a_frequency_is_not_shaped(tmp_path):
    s = _load(tmp_path, "[shaper]\nshaper_freq_y = 50\n")
    assert s.shaper["type"] == ("none", "mzv") and s.shaper["damping"] == (0.1, 0.1)
    cfg = default_machine(s)
    assert cfg.shaper_taps[0] == ((32768,), (0,))  # x passes through
    assert cfg.shaper_taps[1] == tuple(tuple(v) for v in quantize(design("mzv", 50.0, 0.1), 1000))
    s = _load(tmp_path, '[shaper]\nshaper_type = "ei"\nshaper_freq_x = 40\nshaper_freq_y = 0\n')
    assert s.shaper["type"] == ("ei", "none")
    assert default_machine(_load(tmp_path, "[shaper]\nshaper_freq_x = 0\n")).shaper == "none"


def test_the_older_keys_give_the_same_taps_as_the_table(tmp_path):
    old = default_machine(_load(tmp_path, '[motion]\nshaper = "zvd"\n[dynamics]\nf_hz = [40, 35]\nzeta = [0.1, 0.05]\n'))
    new = default_machine(_load(tmp_path, '[shaper]\nshaper_type = "zvd"\nshaper_freq_x = 40\nshaper_freq_y = 35\n'
                                          'damping_ratio_x = 0.1\ndamping_ratio_y = 0.05\n'))
    assert old.shaper == "zvd" and new.shaper == "zvd/zvd" and old.shaper_taps == new.shaper_taps
    assert old.shaper_design == new.shaper_design


@pytest.mark.parametrize("extra,key", [
    ('[shaper]\nshaper_type_x = "zvdd"\nshaper_freq_x = 40\n', "[shaper] shaper_type_x"),
    ('[shaper]\nshaper_type = 3\n', "[shaper] shaper_type"),
    ("[shaper]\nshaper_freq_x = -5\n", "[shaper] shaper_freq_x"),
    ("[shaper]\nshaper_freq_y = 300\n", "[shaper] shaper_freq_y"),  # above a quarter of the 1 kHz samples
    ("[shaper]\nshaper_freq_x = 0.5\n", "[shaper] shaper_freq_x"),
    ('[shaper]\nshaper_freq_x = "fast"\n', "[shaper] shaper_freq_x"),
    ('[shaper]\nshaper_type_y = "3hump_ei"\nshaper_freq_y = 60\ndamping_ratio_y = 0.25\n', "[shaper] damping_ratio_y"),
    ('[shaper]\nshaper_type_x = "ei"\nshaper_freq_x = 60\ndamping_ratio_x = 0.45\n', "[shaper] damping_ratio_x"),
    ("[shaper]\nshaper_freq_x = 40\ndamping_ratio_x = 1.5\n", "[shaper] damping_ratio_x"),
    ("[shaper]\nshaper_freq_x = 40\nshaper_freq_z = 40\n", "[shaper] shaper_freq_z"),
    ('[motion]\nshaper = "zv"\n[dynamics]\nf_hz = 40\nzeta = 0.1\n[shaper]\nshaper_freq_x = 40\n', "[motion] shaper"),
])
def test_bad_values_are_one_line_naming_the_key(tmp_path, extra, key):
    with pytest.raises(NnikError) as exc:
        _load(tmp_path, extra)
    msg = str(exc.value)
    assert key in msg and "\n" not in msg, msg


def test_motion_shaper_none_beside_the_table_is_no_conflict(tmp_path):
    s = _load(tmp_path, '[motion]\nshaper = "none"\n[shaper]\nshaper_freq_x = 40\n')
    assert s.motion["shaper"] == "mzv/none" and default_machine(s).shaper == "mzv/none"


def test_older_form_takes_the_new_kinds(tmp_path):
    cfg = default_machine(_load(tmp_path, '[motion]\nshaper = "2hump_ei"\n[dynamics]\nf_hz = 45\nzeta = 0.1\n'))
    assert cfg.shaper == "2hump_ei" and all(len(a) <= 8 for a, _ in cfg.shaper_taps)
