"""make(): each kind behind one interface; bad gains are one NnikError line naming the problem."""

from __future__ import annotations

import pytest

from nnik.errors import NnikError
from nnik.implementations.servo import KINDS, ServoController, make
from nnik.implementations.servo.emit_c import servo_config_h
from tests.implementations.servo.sequences import CFG, make_plain


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_has_the_interface_and_its_macro(kind):
    ctl = make(kind, make_plain(kind), CFG)
    assert isinstance(ctl, ServoController) and ctl.kind == kind
    d = ctl.c_defines()
    assert d[f"NNIK_CTL_{kind.upper()}"] == 1 and d["NNIK_DUTY_MAX"] == CFG.duty_max
    text = servo_config_h(ctl)
    assert all(f"#define {k} {v}" in text for k, v in d.items())
    ctl.reset()
    assert ctl.tick((0, 0), (0, 0)) == (0, 0)  # at rest on the reference: no duty


def test_pid_gains_are_quantised_as_the_library_scales_them():
    q = make("pid", dict(kp_x=2.0, ki_x=4.0, kd_x=0.02, kp_y=0.5, ki_y=0.0, kd_y=0.0), CFG).c_defines()
    assert (q["NNIK_KP_X"], q["NNIK_KI_X"], q["NNIK_KD_X"]) == (512, round(4.0 * 0.005 * 65536), round(0.02 / 0.005 * 256))
    assert (q["NNIK_KP_Y"], q["NNIK_KI_Y"], q["NNIK_KD_Y"]) == (128, 0, 0)


@pytest.mark.parametrize("change, message", [
    ({"kp_x": -1.0}, "kp_x = -1.0 is outside"),
    ({"kp_x": 300.0}, "kp_x = 300.0 is outside its format's range 0 .. 255.996"),
    ({"ki_y": 250.0}, "ki_y"),
    ({"kp_x": "fast"}, "must be a number"),
    ({"kp_x": float("nan")}, "kp_x"),
    ({"kz": 1.0}, "unknown key 'kz'"),
])
def test_bad_gains_are_one_error(change, message):
    with pytest.raises(NnikError, match=message) as e:
        make("pid", {**make_plain("pid"), **change}, CFG)
    assert "\n" not in str(e.value)


def test_missing_gain_window_and_kind():
    g = make_plain("pid")
    del g["kd_y"]
    with pytest.raises(NnikError, match="missing 'kd_y'"):
        make("pid", g, CFG)
    with pytest.raises(NnikError, match="window must be one of 1, 2, 4, 8"):
        make("pdff", {**make_plain("pdff"), "win": 3}, CFG)
    with pytest.raises(NnikError, match="unknown controller kind 'lqr'"):
        make("lqr", {}, CFG)
    with pytest.raises(NnikError, match="duty_max"):
        make("pid", make_plain("pid"), type("C", (), {"tick_s": 0.005, "duty_max": 70000})())
