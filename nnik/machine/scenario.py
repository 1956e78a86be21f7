"""Scenario files (TOML): the user-facing contract. Every problem is one line naming file and key."""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from nnik.machine.actuator import SCHEMAS as ACTUATOR_SCHEMAS
from nnik.machine.actuator import Actuator
from nnik.emit.c_text import c_name_problem
from nnik.errors import NnikError
from nnik.machine.kinematics import KINDS, Mechanism, Workspace
from nnik.machine import ranges
from nnik.machine.kinematics.measured import check_marks_for_network
from nnik.machine.motion import validate_motion
from nnik.machine.motor_limits import motor_rows
from nnik.machine.servo import ServoConfig, servo_tables
from nnik.machine.shaper_table import validate_shaper
from nnik.machine.params import MAX_LENGTH_MM, Param, positive, validate_table


def _at_least(n):
    return lambda v: None if v >= n else f"must be >= {n}, got {v}"


def _between(lo, hi):
    return lambda v: None if lo <= v <= hi else f"must be in [{lo}, {hi}], got {v}"


MAX_SCENARIO_BYTES = 16 << 20  # a scenario is a page of TOML; its measured data is a CSV beside it
MAX_POINTS = 2_000_000  # per split: float64 positions, targets and activations stay within RAM
MAX_SEED = 2**32 - 1  # numpy, scipy and torch all take it
MAX_WIDTH, MAX_DEPTH = 256, 4  # an 8-bit MCU runs nothing wider, and range analysis stays exact
TRAIN_MEMORY_BYTES = 4 * 2**30  # the training tensors' estimated peak must stay below this


def _hidden(v):
    if len(v) > MAX_DEPTH:
        return f"at most {MAX_DEPTH} hidden layers, got {len(v)}"
    if max(v) > MAX_WIDTH:
        return f"hidden layers of at most {MAX_WIDTH} neurons, got {max(v)}"
    return None


TOP = {
    "name": Param("str", required=True, check=c_name_problem, doc="prefixes generated symbols and the output dir"),
    "description": Param("str", default=""),
    "mechanism": Param("table", required=True),
    "actuator": Param("table", required=True),
    "workspace": Param("table", required=True),
    "dataset": Param("table", default={}),
    "network": Param("table", default={}),
    "training": Param("table", default={}),
    "export": Param("table", default={}),
    "target": Param("table", default={}),
    "tool": Param("table", default={}),
    "motion": Param("table", default={}),
    "dynamics": Param("table", default={}),
    "shaper": Param("table", default={}),
    "servo": Param("table", default=None),  # a dc_servo's plant (nnik.machine.servo)
    "controller": Param("table", default=None),
}
def _extent(v):
    return None if max(abs(v[0]), abs(v[1])) <= MAX_LENGTH_MM else f"must lie within +/-{MAX_LENGTH_MM:g} mm, got {list(v)}"


WORKSPACE = {"x_mm": Param("range", required=True, check=_extent), "y_mm": Param("range", required=True, check=_extent)}
DATASET = {
    "n_train": Param("int", default=1000, check=_between(10, MAX_POINTS)),
    "n_val": Param("int", default=0, check=_between(0, MAX_POINTS), doc="0 = n_train / 4 (at least 200)"),
    "n_test": Param("int", default=20000, check=_between(10, MAX_POINTS)),
    "sampling": Param("str", default="sobol", choices=("sobol", "uniform", "grid")),
    "seed": Param("int", default=0, check=_between(0, MAX_SEED)),
}
NETWORK = {
    "hidden": Param("intlist", default=(6,), check=_hidden, doc="hidden tanh layer sizes"),
    "mode": Param("str", default="full", choices=("full", "residual")),
    "normalize": Param("bool", default=True, doc="normalise inputs to [-1, 1] (seed 004's fix)"),
}
TRAINING = {
    "max_seconds": Param("float", check=positive,
                         doc="optional wall-clock cap, unset by default; the budget is adam_steps, lbfgs_rounds, "
                             "patience, restarts. When the cap cuts training short, the result depends on the "
                             "machine's load: the console, metrics.json and the report say so"),
    "adam_steps": Param("int", default=3000, check=_between(0, 1_000_000)),
    "adam_lr": Param("float", default=0.01, check=positive),
    "lbfgs_rounds": Param("int", default=400, check=_between(0, 100_000), doc="L-BFGS outer iterations"),
    "restarts": Param("int", default=3, check=_between(1, 100), doc="independent initialisations; best kept"),
    "patience": Param("int", default=40, check=_at_least(1), doc="rounds without validation gain"),
}

EXPORT = {
    "tanh": Param("str", default="default", doc="tanh replacement variant (see `nnik tanh`)"),
    "weight_bits": Param("int", default=16, choices=(8, 16), doc="weight storage: int16 or int8"),
    "lut_bytes": Param("int", default=0, check=_at_least(0), doc="ignored: the old LUT baseline retired (a table is the lut family)"),
    "kernel": Param("str", default="fast", choices=("fast", "portable"),
                    doc="fast: hardware-multiply asm on AVR/PIC18 (portable C elsewhere); portable: plain C"),
    "input_unit_um": Param("float", default=1.0, check=lambda v: None if 0.001 <= v <= 1000 else
                           f"must be in [0.001, 1000] um, got {v}",
                           doc="the C's input unit in micrometres (e.g. 0.25 for a 16-bit DAC galvo)"),
}
TARGET = {
    "chip": Param("str", default="avr", choices=("avr", "pic18"), doc="the chip the pick is cheapest on"),
    "max_error": Param("float", default=0.25, check=positive,
                       doc="pre-rounding max |error| in output units on the dense check grid"),
    "max_cycles": Param("float", check=positive, doc="optional limit on measured cycles per call"),
    "max_flash_bytes": Param("int", check=lambda v: None if v > 0 else f"must be > 0, got {v}",
                             doc="optional limit on the model's flash bytes"),
}


TOOL = {  # the G-code firmware's tool on D11 (nnik.firmware.config.MachineConfig)
    "kind": Param("str", default="laser", choices=("laser", "pen", "servo", "spindle", "knife", "none"),
                  doc="laser: M3/M4/M5 with S, Z its focus; pen, spindle, knife: down at or below pen_z_um "
                      "(D11 high); servo: the same, as a servo angle; none: nothing on D11"),
    "m300_down_max": Param("int", default=40, check=ranges.int_range(*ranges.M300_DOWN_RANGE),
                           doc="a servo-pen file's M300 S at or below this puts the pen down (unicorn: 30 down, 50 up)"),
    "s_max": Param("int", default=1000, check=ranges.int_range(*ranges.S_MAX_RANGE),
                   doc="S of full laser power (grbl's $30)"),
    "pen_z_um": Param("int", default=0, check=ranges.tool_z_um_problem,
                      doc="Z above this (um) lifts the pen"),
    "servo_up_deg": Param("int", default=90, check=ranges.int_range(*ranges.SERVO_DEG_RANGE)),
    "servo_down_deg": Param("int", default=30, check=ranges.int_range(*ranges.SERVO_DEG_RANGE)),
}


def training_memory_bytes(n_rows: int, n_val: int, n_test: int, hidden: tuple[int, ...]) -> int:
    """Estimated peak of the training tensors: every layer's float64 activations, their tanh and
    their gradients over the full batch (train and validation), plus the test-set prediction."""
    width = 4 + sum(hidden)
    return 8 * (4 * (n_rows + n_val) * width + 2 * n_test * width)


def _check_training_memory(mechanism, dataset: dict, network: dict, source: str) -> None:
    n_rows = len(mechanism.positions_mm) if not mechanism.analytic else dataset["n_train"]
    need = training_memory_bytes(n_rows, dataset["n_val"], dataset["n_test"], network["hidden"])
    if need > TRAIN_MEMORY_BYTES:
        raise NnikError(f"training would need about {need / 2**30:.1f} GiB (limit {TRAIN_MEMORY_BYTES / 2**30:.0f} GiB); "
                        f"use fewer training points or smaller hidden layers", source, "[network] hidden")


@dataclass
class Scenario:
    name: str
    source: str
    raw: dict
    base_dir: Path
    mechanism: Mechanism
    actuator: Actuator
    workspace: Workspace
    dataset: dict
    network: dict
    training: dict
    export: dict
    target: dict
    tool: dict
    motion: dict | None = None  # [motion] with defaults (nnik.machine.motion)
    dynamics: dict | None = None  # [dynamics]: {"f_hz": (fx, fy), "zeta": (zx, zy)}, or None
    shaper: dict | None = None  # [shaper] per axis (nnik.machine.shaper_table), or None
    servo: ServoConfig | None = None  # a dc_servo's [servo] tables (nnik.machine.servo), or None
    controller: dict | None = None  # a dc_servo's [controller] with defaults, or None

    @property
    def outputs(self) -> list[str]:
        return list(self.mechanism.joint_names)

    @property
    def fingerprint(self) -> str:
        """Hash of what the data and the trained model depend on: the TOML tables other than
        [export], [target], [tool], [motion], [dynamics], [shaper] and the description, and for measured data the CSV's bytes. data.npz
        and model.pt carry it, so every stage can tell they belong together; changing the
        target or the export options needs no new data."""
        import hashlib
        import json

        kept = {k: v for k, v in self.raw.items() if k not in ("export", "target", "tool", "motion", "dynamics", "shaper", "description")}
        h = hashlib.sha256(json.dumps(kept, sort_keys=True, default=str).encode())
        csv = getattr(self.mechanism, "csv_path", None)
        if csv is not None and Path(csv).is_file():
            h.update(Path(csv).read_bytes())
        return h.hexdigest()[:16]

    @property
    def unit(self) -> str:
        return self.actuator.unit

    @classmethod
    def from_dict(cls, raw: dict, source: str, base_dir: Path) -> "Scenario":
        top = validate_table(raw, TOP, source, "top level")
        ws = validate_table(top["workspace"], WORKSPACE, source, "workspace")
        workspace = Workspace(ws["x_mm"], ws["y_mm"])

        act_raw = top["actuator"]
        if not isinstance(act_raw, dict) or "kind" not in act_raw:
            raise NnikError("missing required key", source, "[actuator] kind")
        if not isinstance(act_raw["kind"], str) or act_raw["kind"] not in ACTUATOR_SCHEMAS:
            raise NnikError(f"must be one of {', '.join(ACTUATOR_SCHEMAS)}; got {act_raw['kind']!r}", source, "[actuator] kind")
        act = validate_table(act_raw, ACTUATOR_SCHEMAS[act_raw["kind"]], source, "actuator", act_raw["kind"])
        actuator = Actuator.from_params(act)

        mech_raw = top["mechanism"]
        if not isinstance(mech_raw, dict) or "kind" not in mech_raw:
            raise NnikError("missing required key", source, "[mechanism] kind")
        kind = mech_raw["kind"]
        if not isinstance(kind, str) or kind not in KINDS:
            raise NnikError(f"must be one of {', '.join(KINDS)}; got {kind!r}", source, "[mechanism] kind")
        cls_ = KINDS[kind]
        schema = {"kind": Param("str", required=True), **cls_.PARAMS}
        mech = validate_table(mech_raw, schema, source, "mechanism", kind)
        mech.pop("kind")
        if cls_.family == "belt":
            if actuator.kind != "stepper":
                raise NnikError("belt machines are driven by steppers, not a DAC", source, "[actuator] kind")
            for r in ("R1_mm", "R2_mm"):
                if mech[r] is None:
                    if act["mm_per_rev"] is None:
                        raise NnikError(f"give [mechanism] {r} or [actuator] mm_per_rev", source, f"[mechanism] {r}")
                    mech[r] = act["mm_per_rev"] / (2 * math.pi)
        if cls_.family == "measured":
            mech["csv"] = str((base_dir / mech["csv"]).resolve())
        mechanism = cls_(mech, workspace, source)
        if cls_.family == "belt":  # before Newton meets an absurd scale (mm_per_rev = 1e-9)
            affine = mechanism.affine_inverse(workspace.boundary()) - mechanism.q_rest
            actuator.check_range(actuator.to_units(affine), source)
        mechanism.check_reach()
        servo, controller = servo_tables(top, actuator, mechanism, source)
        if mechanism.analytic:
            units = actuator.to_units(mechanism.inverse(workspace.boundary()) - mechanism.q_rest)
            actuator.check_range(units, source)
        else:
            actuator.check_range(mechanism.commands, str(mechanism.csv_path), "q1/q2 columns", "the rows command")

        dataset = validate_table(top["dataset"], DATASET, source, "dataset")
        if dataset["n_val"] == 0:
            dataset["n_val"] = max(200, dataset["n_train"] // 4)
        network = validate_table(top["network"], NETWORK, source, "network")
        _check_training_memory(mechanism, dataset, network, source)
        check_marks_for_network(mechanism, network, source)
        training = validate_table(top["training"], TRAINING, source, "training")
        export = validate_table(top["export"], EXPORT, source, "export")
        problem = ranges.input_units_problem(float(max(abs(v) for v in (*workspace.x_mm, *workspace.y_mm))),
                                             export["input_unit_um"])
        if problem:
            raise NnikError(problem, source, "[export] input_unit_um")
        target = validate_table(top["target"], TARGET, source, "target")
        tool = validate_table(top["tool"], TOOL, source, "tool")
        motion, dynamics = validate_motion(top["motion"], top["dynamics"], source)
        shaper = validate_shaper(top["shaper"], motion, top["motion"], source)
        motor_rows(mechanism, actuator, workspace, motion, source)  # the motor limits' check
        if export["tanh"] != "default" and export["tanh"] not in ranges.TANH_VARIANTS:
            raise NnikError(f"unknown tanh variant; choose one of default, {', '.join(ranges.TANH_VARIANTS)}",
                            source, "[export] tanh")
        return cls(
            name=top["name"],
            source=source,
            raw=raw,
            base_dir=base_dir,
            mechanism=mechanism,
            actuator=actuator,
            workspace=workspace,
            dataset=dataset,
            network=network,
            training=training,
            export=export,
            target=target,
            tool=tool,
            motion=motion,
            dynamics=dynamics,
            shaper=shaper,
            servo=servo,
            controller=controller,
        )


def load_scenario(path: str | Path) -> Scenario:
    path = Path(path)
    source = str(path)
    if path.is_dir():
        raise NnikError("a directory, not a scenario file", source)
    if not path.is_file():
        raise NnikError("scenario file not found", source)
    try:
        if path.stat().st_size > MAX_SCENARIO_BYTES:
            raise NnikError(f"{path.stat().st_size} bytes: no scenario is that large (at most "
                            f"{MAX_SCENARIO_BYTES >> 20} MiB)", source)
        raw = tomllib.loads(path.read_text())  # universal newlines: LF, CRLF, CR alone and mixed
    except tomllib.TOMLDecodeError as exc:
        raise NnikError(f"malformed TOML: {exc}", source) from None
    except UnicodeDecodeError:
        raise NnikError("not a UTF-8 text file", source) from None
    except OSError as exc:
        raise NnikError(f"cannot read: {exc.strerror or exc}", source) from None
    return Scenario.from_dict(raw, source, path.parent.resolve())
