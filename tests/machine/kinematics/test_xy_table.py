"""The XY table's kinematics: the screw's angle is position / lead, with a stepper or a DC servo."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, strategies as st

from nnik.machine.scenario import Scenario
from tests.conftest import DATASETS
import tomllib

SHIPPED = tomllib.loads((DATASETS / "xy_table.toml").read_text())


@given(lead=st.floats(0.1, 100.0), x=st.floats(0.0, 200.0), y=st.floats(0.0, 150.0))
def test_forward_inverts_inverse_and_a_turn_is_a_lead(lead, x, y):
    raw = {**SHIPPED, "mechanism": {"kind": "xy_table", "lead_mm": lead}}
    s = Scenario.from_dict(raw, "t.toml", DATASETS)
    q = s.mechanism.inverse([[x, y]])
    np.testing.assert_allclose(q, [[2 * math.pi * x / lead, 2 * math.pi * y / lead]], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(s.mechanism.forward(q), [[x, y]], rtol=1e-12, atol=1e-12)


def test_the_shipped_table_counts_2_5_um_and_200_mm_is_80000_counts():
    s = Scenario.from_dict(SHIPPED, "t.toml", DATASETS)
    assert s.actuator.unit == "count" and s.servo.um_per_count == 2.5
    units = s.actuator.to_units(s.mechanism.inverse([[200.0, 150.0]]))
    np.testing.assert_allclose(units, [[80_000, 60_000]])
    assert s.servo.duty_max == 255 and s.servo.tick_s == 0.005


def test_a_stepper_drives_an_xy_table_open_loop():
    raw = {k: v for k, v in SHIPPED.items() if k not in ("servo", "controller")}
    raw["actuator"] = {"kind": "stepper", "steps_per_rev": 200, "microsteps": 16}
    s = Scenario.from_dict(raw, "t.toml", DATASETS)
    assert s.servo is None and s.controller is None
    np.testing.assert_allclose(s.actuator.to_units(s.mechanism.inverse([[3.0, 1.5]])), [[3200, 1600]])
