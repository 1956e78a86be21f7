"""The report's physical unit of an XY table: table travel per count or microstep."""

from __future__ import annotations

import tomllib

import pytest

from nnik.machine.scenario import Scenario
from nnik.report.units import physical_units
from tests.conftest import DATASETS

SHIPPED = tomllib.loads((DATASETS / "xy_table.toml").read_text())
STEPPER = {**{k: v for k, v in SHIPPED.items() if k not in ("servo", "controller")},
           "actuator": {"kind": "stepper", "steps_per_rev": 200, "microsteps": 16}}


@pytest.mark.parametrize("raw,um", [(SHIPPED, 2.5), (STEPPER, 3000 / 3200)])
def test_an_xy_tables_unit_is_table_travel(raw, um):
    phys, why = physical_units(Scenario.from_dict(raw, "t.toml", DATASETS), 2)
    assert why == "" and phys.factors == pytest.approx([um, um], rel=1e-12)
    assert "table travel" in phys.resolution
