"""A DC-servo XY table's [servo] tables and [controller] table (issue 28), checked as one: the keys
and their ranges are in nnik.machine.servo_params; this module adds the checks that involve several
keys (break-away within the motor's reach, substeps against the time constants, the 8-bit
counter's wrap at full speed, a whole number of encoder counts per motor turn) and builds the
`ServoConfig` (nnik.dynamics.servo.config, re-exported here) of `MotorAxis` per axis.
"""

from __future__ import annotations

import math

from nnik.dynamics.servo.config import MotorAxis, ServoConfig
from nnik.dynamics.servo.speed_model import SpeedModel
from nnik.errors import NnikError
from nnik.machine import servo_params as sp
from nnik.machine.params import validate_table

AXES = ("x", "y")
__all__ = ["AXES", "MotorAxis", "ServoConfig", "servo_problems", "servo_tables", "validate_servo"]


def _axis_problems(ax: MotorAxis, name: str, cfg: ServoConfig) -> list[tuple[str, str]]:
    at = f"[servo.{name}]"
    out = []
    if ax.stiction_n_m and ax.stiction_n_m < ax.coulomb_n_m:
        out.append((f"{at} stiction_n_m", f"must be 0 (off) or at least coulomb_n_m ({ax.coulomb_n_m:g} N m): "
                                          f"break-away lies above sliding friction, got {ax.stiction_n_m:g}"))
    stall = ax.ke_v_s_rad * cfg.supply_v / ax.ra_ohm
    if ax.break_away_n_m >= stall:
        out.append((f"{at} {'stiction_n_m' if ax.stiction_n_m else 'coulomb_n_m'}",
                    f"the motor never moves: its stall torque at {cfg.supply_v:g} V is {stall:.4g} N m, "
                    f"the break-away {ax.break_away_n_m:.4g} N m"))
    per_motor = cfg.counts_per_rev / ax.gear_ratio
    if abs(per_motor - round(per_motor)) > 1e-6 * per_motor or round(per_motor) < 1:
        out.append((f"{at} gear_ratio", f"counts_per_rev {cfg.counts_per_rev} / gear_ratio {ax.gear_ratio:g} = "
                                        f"{per_motor:.6g} counts per motor turn: the encoder on the motor shaft "
                                        "counts a whole number"))
    h = cfg.tick_s / cfg.substeps
    if h > ax.tau_e_s:
        need = math.ceil(cfg.tick_s / ax.tau_e_s)
        out.append(("[servo] substeps", f"{cfg.substeps} substeps of {h * 1e3:.4g} ms are longer than {name}'s "
                                        f"electrical time constant La/Ra = {ax.tau_e_s * 1e3:.4g} ms; use at least {need}"))
    elif h > ax.tau_m_s / sp.SUBSTEPS_PER_TAU_M:
        need = math.ceil(cfg.tick_s * sp.SUBSTEPS_PER_TAU_M / ax.tau_m_s)
        out.append(("[servo] substeps", f"{cfg.substeps} substeps of {h * 1e3:.4g} ms are longer than 1/"
                                        f"{sp.SUBSTEPS_PER_TAU_M} of {name}'s speed time constant "
                                        f"{ax.tau_m_s * 1e3:.4g} ms; use at least {need}"))
    if cfg.encoder == "counter8":
        per_tick = cfg.free_speed_counts_s(AXES.index(name)) * cfg.tick_s
        if per_tick >= 128:
            out.append(("[servo] encoder", f"counter8: {name} runs {per_tick:.0f} counts a tick at full speed, so "
                                           "its 8-bit counter wraps past half a turn between reads and cannot be "
                                           "unwrapped; use quadrature or a shorter tick"))
    return out


def servo_problems(cfg: ServoConfig) -> list[tuple[str, str]]:
    """(key, problem) for every check that involves several keys; [] when the plant makes sense."""
    out = []
    for i, name in enumerate(AXES):
        out += _axis_problems(cfg.axes[i], name, cfg)
    return out


def _axis(table, source: str, name: str) -> tuple[MotorAxis, SpeedModel | None]:
    p = validate_table(table, sp.AXIS, source, f"servo.{name}")
    ident = p.pop("identified")
    model = None
    if ident is not None:
        q = validate_table(ident, sp.IDENTIFIED, source, f"servo.{name}.identified")
        model = SpeedModel(q["k_counts_s_v"], q["tau_s"])
    return MotorAxis(**p), model


def validate_servo(servo_raw, controller_raw, counts_per_rev: int, lead_mm: float,
                   source: str) -> tuple[ServoConfig, dict]:
    """The [servo] tables as a ServoConfig and [controller] with defaults; one NnikError line for
    the first problem."""
    s = validate_table(servo_raw, sp.SERVO, source, "servo")
    axes, models = zip(*(_axis(s[n], source, n) for n in AXES))
    cfg = ServoConfig(axes=tuple(axes), tick_s=s["tick_s"], supply_v=s["supply_v"],
                      duty_max=(1 << s["pwm_bits"]) - 1, encoder=s["encoder"], substeps=s["substeps"],
                      counts_per_rev=counts_per_rev, lead_mm=lead_mm, identified=tuple(models))
    for key, problem in servo_problems(cfg):
        raise NnikError(problem, source, key)
    controller = validate_table(controller_raw, sp.CONTROLLER, source, "controller")
    return cfg, controller


def servo_tables(top: dict, actuator, mechanism, source: str) -> tuple[ServoConfig | None, dict | None]:
    """A scenario's ServoConfig and [controller] (None, None without a dc_servo actuator): a DC servo
    drives an xy_table and needs [servo]; the servo tables mean nothing to other actuators."""
    if actuator.kind != "dc_servo":
        for table in ("servo", "controller"):
            if top.get(table) is not None:
                raise NnikError(f"only a dc_servo actuator has a [{table}] table (this one is {actuator.kind})",
                                source, f"[{table}]")
        return None, None
    if mechanism.kind != "xy_table":
        raise NnikError(f"a dc_servo drives an xy_table's screws, not a {mechanism.kind}", source, "[actuator] kind")
    if top.get("servo") is None:
        raise NnikError("missing required table: a dc_servo needs its motors", source, "[servo]")
    return validate_servo(top["servo"], top.get("controller") or {}, actuator.params["counts_per_rev"],
                          mechanism.params["lead_mm"], source)
