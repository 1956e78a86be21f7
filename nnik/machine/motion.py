"""The scenario's [motion] and [dynamics] tables: what the G-code firmware's planner and shaper
may do, and how the machine's axes ring.

[motion]  accel_x_mm_s2, accel_y_mm_s2   max acceleration per Cartesian axis (default 1000 mm/s^2)
          junction_deviation_mm          grbl's junction rule (default 0.01 mm)
          max_feed_mm_min                caps F; G0 moves at it (default 3000 mm/min)
          sample_hz                      the fixed-rate trajectory (default 1000 Hz)
          shaper                         none | zv | mzv | zvd | ei | 2hump_ei | 3hump_ei | auto (default
                                         none; per axis, as Klipper: the [shaper] table instead)
          max_contour_um                 auto's contour-error target (optional)
          motor_max_speed, motor_max_accel   per motor, in its own units per s / s^2 (optional;
                                         nnik.machine.motor_limits: microsteps, mirror degrees, counts)
[dynamics] f_hz = [fx, fy], zeta = [zx, zy]
          One base-excited spring-damper per Cartesian axis (seed 003; the model Klipper measures
          and shapes per X and Y, CoreXY included: its two belts move the head together in X and
          in Y, so the modes that ring are the head's Cartesian ones).  f in Hz (the undamped
          natural frequency fn = wn / 2 pi), zeta the damping ratio.  A scalar applies to both axes.
"""

from __future__ import annotations

from nnik.dynamics.shapers import KINDS
from nnik.errors import NnikError
from nnik.machine import motor_limits, ranges
from nnik.machine.params import Param, validate_table, within

SHAPERS = ("none",) + KINDS + ("auto",)
TICK_HZ = ranges.TICK_HZ

# the ranges of the feeds, accelerations and junction deviation are the firmware's integers'
# (nnik.machine.ranges), checked together below: the acceleration's and the feed's depend on sample_hz
MOTION = {
    "accel_x_mm_s2": Param("float", default=1000.0),
    "accel_y_mm_s2": Param("float", default=1000.0),
    "junction_deviation_mm": Param("float", default=0.01),
    "max_feed_mm_min": Param("float", default=3000.0),
    "sample_hz": Param("int", default=1000, check=ranges.sample_hz_problem),
    "shaper": Param("str", default="none", choices=SHAPERS),
    "max_contour_um": Param("float", check=within(0.0, 1e6, open_lo=True, unit=" um"), doc="auto's target"),
}
MOTOR = motor_limits.PARAMS  # parsed and checked by nnik.machine.motor_limits
DYNAMICS = {
    "f_hz": Param("pair", required=True, doc="undamped natural frequency per axis, Hz"),
    "zeta": Param("pair", required=True, doc="damping ratio per axis"),
}


def _pair(value, key: str, source: str) -> tuple[float, float]:
    vals = value if isinstance(value, list) else [value]
    if len(vals) == 1:
        vals = vals * 2
    if len(vals) != 2 or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in vals):
        raise NnikError(f"expected a number or [x, y], got {value!r}", source, f"[dynamics] {key}")
    out = tuple(float(v) for v in vals)
    if any(v != v or v in (float("inf"), float("-inf")) for v in out):
        raise NnikError(f"must be finite, got {value!r}", source, f"[dynamics] {key}")
    return out


def validate_motion(motion_raw, dynamics_raw, source: str) -> tuple[dict, dict | None]:
    """([motion] with defaults, [dynamics] as {"f_hz": (fx, fy), "zeta": (zx, zy)} or None)."""
    motor = motor_limits.parse_keys(motion_raw, source) if isinstance(motion_raw, dict) else {}
    rest = {k: v for k, v in motion_raw.items() if k not in motor} if isinstance(motion_raw, dict) else motion_raw
    motion = {**validate_table(rest, MOTION, source, "motion", also=tuple(MOTOR)), **motor}
    for key, problem in ranges.motion_problems(**ranges.motion_ints(motion)):
        raise NnikError(problem, source, f"[motion] {key}")
    if dynamics_raw is None or dynamics_raw == {}:
        if motion["shaper"] != "none":
            raise NnikError(f"shaper {motion['shaper']!r} needs a [dynamics] table (f_hz, zeta)", source, "[motion] shaper")
        return motion, None
    if not isinstance(dynamics_raw, dict):
        raise NnikError(f"expected a table, got {dynamics_raw!r}", source, "[dynamics]")
    for key in dynamics_raw:
        if key not in DYNAMICS:
            raise NnikError(f"unknown key (allowed: {', '.join(DYNAMICS)})", source, f"[dynamics] {key}")
    for key in DYNAMICS:
        if key not in dynamics_raw:
            raise NnikError("missing required key", source, f"[dynamics] {key}")
    f = _pair(dynamics_raw["f_hz"], "f_hz", source)
    zeta = _pair(dynamics_raw["zeta"], "zeta", source)
    nyquist = motion["sample_hz"] / 2
    for v in f:
        if not 1.0 <= v < nyquist / 2:
            raise NnikError(f"must be in [1, {nyquist / 2:g}) Hz, a quarter of the {motion['sample_hz']} Hz sample rate "
                            f"(half its Nyquist limit, so a shaper's taps resolve the period), got {v:g}",
                            source, "[dynamics] f_hz")
    for v in zeta:
        if not 0.0 <= v <= 2.0:
            raise NnikError(f"must be in [0, 2], got {v:g}", source, "[dynamics] zeta")
        if v >= 1.0 and motion["shaper"] != "none":
            raise NnikError(f"zeta {v:g} >= 1 is overdamped: the axis does not ring, so there is nothing to shape; "
                            "set [motion] shaper = \"none\"", source, "[dynamics] zeta")
    dynamics = {"f_hz": f, "zeta": zeta}
    if motion["shaper"] not in ("none", "auto"):
        from nnik.dynamics.shapers import axis_taps

        ints = ranges.motion_ints(motion)
        try:
            taps = axis_taps(motion["shaper"], dynamics, motion["sample_hz"])
        except ValueError as exc:  # a damping ratio beyond what the shaper's design allows
            raise NnikError(str(exc), source, "[motion] shaper") from None
        problem = ranges.shaper_problem(taps, ints["feed_um_min"], motion["sample_hz"])
        if problem:
            raise NnikError(problem, source, "[motion] shaper")
    return motion, dynamics
