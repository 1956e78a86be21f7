"""Every key a scenario TOML accepts, read from the schemas the scenario check validates against
(nnik.machine.scenario and the tables it hands on), as (section, key, Param)."""

from __future__ import annotations

from nnik.machine import scenario
from nnik.machine.actuator import SCHEMAS as ACTUATORS
from nnik.machine.kinematics import KINDS
from nnik.machine.kinematics.belt import DISTORTION
from nnik.machine.motion import DYNAMICS, MOTION, MOTOR
from nnik.machine.params import Param
from nnik.machine.servo_params import AXIS, CONTROLLER, IDENTIFIED, SERVO
from nnik.machine.shaper_table import SHAPER

TABLES = {
    "workspace": scenario.WORKSPACE, "dataset": scenario.DATASET, "network": scenario.NETWORK,
    "training": scenario.TRAINING, "export": scenario.EXPORT, "target": scenario.TARGET,
    "tool": scenario.TOOL, "motion": {**MOTION, **MOTOR}, "dynamics": DYNAMICS, "shaper": SHAPER,
    "mechanism.distortion": DISTORTION,
    # [servo.y] and [servo.y.identified] take the same keys as X's (the page says so)
    "servo": {k: p for k, p in SERVO.items() if p.kind != "table"},
    "servo.x": {k: p for k, p in AXIS.items() if p.kind != "table"},
    "servo.x.identified": IDENTIFIED, "controller": CONTROLLER,
}


def _union(schemas) -> dict[str, Param]:
    out: dict[str, Param] = {}
    for schema in schemas:
        for key, p in schema.items():
            out.setdefault(key, p)
    return out


def scenario_keys() -> list[tuple[str, str, Param]]:
    """(section, key, Param): "top" for the top level; tables are sections, not keys."""
    keys = [("top", k, p) for k, p in scenario.TOP.items() if p.kind != "table"]
    mechanism = _union([{"kind": Param("str", required=True)}, *(c.PARAMS for c in KINDS.values())])
    keys += [("mechanism", k, p) for k, p in mechanism.items() if p.kind != "table"]
    keys += [("actuator", k, p) for k, p in _union(ACTUATORS.values()).items()]
    for section, schema in TABLES.items():
        keys += [(section, k, p) for k, p in schema.items()]
    assert set(scenario.TOP) - {k for _, k, _ in keys} <= {s.split(".")[0] for s in TABLES} | {"mechanism", "actuator"}
    return keys
