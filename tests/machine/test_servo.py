"""A DC-servo scenario's [servo] and [controller] tables: nonsense plant values and a tick the chip
cannot meet are refused with one line naming file and key, exit 2 (through the CLI's scenario
load, `nnik generate`), before anything is written."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from nnik.machine.scenario import load_scenario
from nnik.machine.servo_params import timer1_setting
from tests.bad_input import fails
from tests.conftest import DATASETS, ROOT, write_toml

XY = (DATASETS / "xy_table.toml").read_text()


def table_sub(text: str, section: str, key: str, value: str) -> str:
    """The scenario with `key = value` in its [section] table (added if the table lacks it)."""
    m = re.search(rf"(?m)^\[{re.escape(section)}\][^\n]*\n", text)
    head, rest = text[:m.end()], text[m.end():]
    body, sep, tail = rest.partition("\n[")
    if re.search(rf"(?m)^{key} = ", body):
        body = re.sub(rf"(?m)^{key} = [^#\n]*", f"{key} = {value} ", body)
    else:
        body = f"{key} = {value}\n" + body
    return head + body + sep + tail


def servo_sub(text: str, key: str, value: str) -> str:
    return table_sub(text, "servo", key, value)


def refused(tmp_path, capsys, text, *needles):
    toml = write_toml(tmp_path, text)
    out = tmp_path / "out"
    fails(capsys, ["generate", toml, "-o", out], str(toml), *needles, watch=out)
    assert not out.exists()


def test_the_shipped_scenario_loads():
    s = load_scenario(DATASETS / "xy_table.toml")
    assert s.mechanism.kind == "xy_table" and s.actuator.kind == "dc_servo"
    assert s.controller["kind"] == "auto" and s.motion["sample_hz"] == 200
    assert s.servo.axes[0] != s.servo.axes[1]


@pytest.mark.parametrize("section,key,value,needle", [
    ("servo.x", "ra_ohm", "-2.2", "must be in (0, 1000] ohm"),
    ("servo.y", "ra_ohm", "0.0", "must be in (0, 1000] ohm"),
    ("servo.x", "j_kg_m2", "0.0", "must be in (0, 1] kg m^2"),
    ("servo.x", "la_h", "0.0", "must be in (0, 10] H"),
    ("servo.y", "la_h", "-0.001", "must be in (0, 10] H"),
    ("servo.x", "ke_v_s_rad", "0.0", "must be in (0, 10] V s/rad"),
    ("servo.y", "viscous_n_m_s_rad", "-1e-7", "must be in [0, 1]"),
    ("servo.x", "coulomb_n_m", "-0.001", "must be in [0, 100]"),
    ("servo.x", "backlash_um", "-5.0", "must be in [0, 10000]"),
    ("servo.y", "gear_ratio", "0.0", "must be in (0, 10000]"),
    ("servo.x", "ra_ohm", '"2.2"', "expected a number"),
    ("servo.x", "stiction_n_m", "0.001", "at least coulomb_n_m"),
    ("servo.y", "stiction_n_m", "0.1", "the motor never moves"),
    ("servo.x", "gear_ratio", "18.7", "whole number"),
    ("servo.y", "torque", "1.0", "unknown key"),
    ("servo", "tick_s", "0.0004", "must be in [0.0005,"),
    ("servo", "tick_s", "0.00123456", "Timer1 makes exactly"),
    ("servo", "tick_s", "5.0", "4.1943] s"),
    ("servo", "tick_s", "0.0", "must be in"),
    ("servo", "substeps", "2", "must be in [4, 1000]"),
    ("servo", "pwm_bits", "10", "must be one of 8"),
    ("servo", "supply_v", "-12.0", "must be in (0, 60] V"),
    ("servo", "encoder", '"gray"', "must be one of quadrature, counter8"),
    ("controller", "kind", '"lqr"', "must be one of auto, pid, pdff, ccc, nn_axes, nn_vector"),
    ("controller", "tune_trials", "0", "must be in [1, 10000]"),
    ("controller", "max_saturated_fraction", "1.5", "must be in [0, 1]"),
])
def test_nonsense_values_are_refused(tmp_path, capsys, section, key, value, needle):
    refused(tmp_path, capsys, table_sub(XY, section, key, value), f"[{section}] {key}", needle)


def test_substeps_too_few_for_the_electrical_time_constant_are_refused(tmp_path, capsys):
    refused(tmp_path, capsys, servo_sub(XY, "substeps", "5"), "[servo] substeps", "electrical time constant",
            "use at least 10")


def test_a_tick_the_chip_cannot_meet_through_python_m_nnik(tmp_path):
    toml = write_toml(tmp_path, servo_sub(XY, "tick_s", "0.0002"))
    r = subprocess.run([sys.executable, "-m", "nnik", "generate", str(toml), "-o", str(tmp_path / "o")],
                       cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert r.stderr.startswith(f"nnik: error: {toml}: [servo] tick_s: must be in [0.0005,"), r.stderr
    assert not (tmp_path / "o").exists()


def test_an_8_bit_counter_that_wraps_past_half_a_turn_a_tick_is_refused(tmp_path, capsys):
    text = servo_sub(servo_sub(XY, "encoder", '"counter8"'), "tick_s", "0.02")
    refused(tmp_path, capsys, servo_sub(text, "substeps", "160"), "[servo] encoder", "cannot be unwrapped")


def test_the_identified_model_is_read_and_checked(tmp_path, capsys):
    good = XY + "\n[servo.x.identified]\nk_counts_s_v = 9000.0\ntau_s = 0.03\n"
    s = load_scenario(write_toml(tmp_path, good))
    assert s.servo.identified[0].tau_s == 0.03 and s.servo.identified[1] is None
    refused(tmp_path, capsys, good.replace("tau_s = 0.03", "tau_s = 0.0"), "[servo.x.identified] tau_s")
    refused(tmp_path, capsys, good.replace("tau_s = 0.03", ""), "[servo.x.identified] tau_s", "missing")


def test_the_tables_go_together(tmp_path, capsys):
    no_servo = re.sub(r"(?s)\[servo\].*?(?=\[controller\])", "", XY)
    refused(tmp_path, capsys, no_servo, "[servo]", "missing required table")
    no_y = re.sub(r"(?s)\[servo\.y\].*?(?=\[controller\])", "", XY)
    refused(tmp_path, capsys, no_y, "[servo] y", "missing required key")
    stepper = XY.replace('kind = "dc_servo"', 'kind = "stepper"').replace("counts_per_rev = 1200", "")
    refused(tmp_path, capsys, stepper, "[servo]", "only a dc_servo actuator")
    hbot = XY.replace('kind = "xy_table"\nlead_mm = 3.0', 'kind = "hbot"\nX_mm = 400.0\nC_mm = 60.0\nR1_mm = 6.0\nR2_mm = 6.0')
    refused(tmp_path, capsys, hbot, "[actuator] kind")


def test_timer1_makes_the_design_ticks():
    assert timer1_setting(0.005) == (8, 9999) and timer1_setting(0.001) == (8, 1999)
    assert timer1_setting(0.00123456) is None and timer1_setting(0.0012345) == (8, 2468)
