"""One truth for the ranges the G-code firmware's integers can hold.

The scenario check ([motion], [tool]), the Python model of the firmware (nnik.firmware.config),
the Arduino export and the job's options (--scale, --offset, --tool-z) all read their limits from
here, so a value the scenario check accepts is one the firmware can run.  Every limit is derived
from an integer format of the C (codegen/arduino/src/nnik_plan.h, nnik_gcode.c):

- speeds are Q16 micrometres per sample, below 2^24 (the sampler's products stay in 32 bits):
  the max feed F (um/min) has floor(F * 65536 / (60 * sample_hz)) < 2^24, and F >= 1 mm/min;
- accelerations are Q16 micrometres per sample squared, floor(a * 65536 / sample_hz^2) in
  [16, 2^22): below 16 the hold's and the brake's roundings swallow it, at 2^22 a * sqrt(2)
  leaves the 32-bit division of the block's braking distance;
- the junction deviation is whole micrometres, 1..1000 (vj^2 = acc * JDEV_UM * r fits 64 bits;
  0 would stop at every corner and divide by zero in the export's hold rate);
- the job's frame scale is Q16, 1..2^24 (1/65536..256); shifts and the tool's Z are int32 um
  within the largest machine (MAX_LENGTH_MM), so Z_HOME = pen_z + 5000 um and p * scale fit.

The TOML and the command line give millimetres; `um` rounds them to the firmware's integers the
one way every stage uses, and the checks below judge the rounded integers.
"""

from __future__ import annotations

import math

from nnik.machine.params import MAX_LENGTH_MM

TICK_HZ = 10_000  # the firmware's stepper interrupt; sample_hz must divide it
MIN_SAMPLE_HZ = 100
Q16 = 1 << 16
SPEED_Q16_LIMIT = 1 << 24  # Q16 um/sample: speeds stay below it
ACC_Q16_MIN, ACC_Q16_LIMIT = 16, 1 << 22  # Q16 um/sample^2: [16, 2^22)
MIN_FEED_UM_MIN = 1000  # 1 mm/min
JDEV_UM_MIN, JDEV_UM_MAX = 1, 1000
SCALE_Q16_MIN, SCALE_Q16_MAX = 1, 1 << 24  # 1/65536 .. 256
SCALE_MIN, SCALE_MAX = SCALE_Q16_MIN / Q16, SCALE_Q16_MAX / Q16
OFFSET_MM_MAX = MAX_LENGTH_MM  # a shift larger than the largest machine leaves every workspace
SEG_UM_MIN, SEG_UM_MAX = 100, 5000  # the longest arc chord (nnik_gc_geom.c refuses others with #error)
TOOL_Z_MM_MAX = 1000.0  # pen_z_um within +-1 m: int32 with room for Z_HOME and the job's Z
# [export] tanh: the MLP's tanh replacements by name (their specs are the MLP family's
# implementations/mlp/tanh_spec.SPECS, in this order; a test holds the two lists equal)
TANH_VARIANTS = ("paper_lsq5", "paper_minimax5", "paper_minimax5_c", "lsq3_x11", "minimax3_x11", "minimax2_x22",
                 "minimax2_x44", "lerp32", "lerp64", "lerp_mr", "lerp_mr4")
TOOL_Z_UM_MAX = int(TOOL_Z_MM_MAX * 1000)


INT32_MAX = (1 << 31) - 1  # the C API's inputs: int32_t in_um[2], in [export] input_unit_um units


def input_units_problem(extent_mm: float, unit_um: float) -> str | None:
    """The workspace's farthest coordinate in the C's input unit must fit int32_t."""
    units = extent_mm * 1000.0 / unit_um
    if units <= INT32_MAX:
        return None
    return (f"the workspace reaches {extent_mm:g} mm = {units:.4g} units of {unit_um:g} um, beyond the C's int32 "
            f"inputs (at most {INT32_MAX}); use a coarser input unit (at least {extent_mm * 1000.0 / INT32_MAX:.3g} um)")


def um(mm: float, per_mm: float = 1000.0) -> int:
    """Millimetres (or mm/min, mm/s^2) as the firmware's whole micrometres: rounded half to even."""
    return int(round(float(mm) * per_mm))


def acc_q16(accel_um_s2: int, sample_hz: int) -> int:
    return int(accel_um_s2) * Q16 // (sample_hz * sample_hz)


def vn_q16(feed_um_min: int, sample_hz: int) -> int:
    return int(feed_um_min) * Q16 // (60 * sample_hz)


def accel_um_s2_range(sample_hz: int) -> tuple[int, int]:
    """The whole um/s^2 whose Q16 per-sample form lies in [ACC_Q16_MIN, ACC_Q16_LIMIT)."""
    s2 = sample_hz * sample_hz
    return -(-ACC_Q16_MIN * s2 // Q16), (ACC_Q16_LIMIT * s2 - 1) // Q16


def feed_um_min_range(sample_hz: int) -> tuple[int, int]:
    """The whole um/min of a max feed whose Q16 per-sample speed stays below SPEED_Q16_LIMIT."""
    return MIN_FEED_UM_MIN, (SPEED_Q16_LIMIT * 60 * sample_hz - 1) // Q16


def sample_hz_problem(sample_hz: int) -> str | None:
    if sample_hz >= MIN_SAMPLE_HZ and TICK_HZ % sample_hz == 0:
        return None
    return (f"must divide the {TICK_HZ} Hz tick rate and be >= {MIN_SAMPLE_HZ} Hz (e.g. 500, 1000, 2000), "
            f"got {sample_hz}")


def _mm(v_um: float) -> str:
    return f"{v_um / 1000:.6f}".rstrip("0").rstrip(".")


def _outside(v: int, lo: int, hi: int, unit: str, why: str) -> str | None:
    return None if lo <= v <= hi else f"must be in [{_mm(lo)}, {_mm(hi)}] {unit} ({why}), got {_mm(v)}"


def accel_problem(accel_um_s2: int, sample_hz: int) -> str | None:
    return _outside(accel_um_s2, *accel_um_s2_range(sample_hz), "mm/s^2",
                    f"at {sample_hz} Hz samples: the firmware's Q16 um/sample^2 in [{ACC_Q16_MIN}, 2^22)")


def feed_problem(feed_um_min: int, sample_hz: int) -> str | None:
    return _outside(feed_um_min, *feed_um_min_range(sample_hz), "mm/min",
                    f"at {sample_hz} Hz samples: the firmware's Q16 um/sample speed below 2^24")


def jdev_problem(jdev_um: int) -> str | None:
    return _outside(jdev_um, JDEV_UM_MIN, JDEV_UM_MAX, "mm", "whole um, the firmware's unit")


def motion_problems(accel_um_s2: tuple[int, int], jdev_um: int, feed_um_min: int, sample_hz: int):
    """[(the [motion] key, its problem)] of the firmware's integers; [] when the firmware runs them."""
    found = [("sample_hz", sample_hz_problem(sample_hz))]
    if found[0][1] is None:
        found += [(k, accel_problem(a, sample_hz)) for k, a in zip(("accel_x_mm_s2", "accel_y_mm_s2"), accel_um_s2)]
        found.append(("max_feed_mm_min", feed_problem(feed_um_min, sample_hz)))
    found.append(("junction_deviation_mm", jdev_problem(jdev_um)))
    return [(k, p) for k, p in found if p]


# [motion] motor_max_speed / motor_max_accel (nnik.machine.motor_limits): in the actuator's own units
# per s and per s^2 (microsteps, mirror degrees, encoder counts); per motor, the head's equivalent
# bound along its worst direction must leave the firmware a speed and an acceleration it can run
MOTOR_SPEED_RANGE = (1e-6, 1e9)
MOTOR_ACCEL_RANGE = (1e-6, 1e12)
MOTOR_Q15 = 1 << 15  # the motor rows' coefficients (nnik_plan.c motor_caps)
SQRT2_UP = 1.41431  # >= sqrt(2) (1 + 2 / 2^15): a block's n_i / Lq at most this
MOTOR_V_Q16_MIN = 2  # the worst direction's speed cap, Q16 um/sample, floor(V / SQRT2_UP) >= 1
MOTOR_A_Q16_MIN = math.ceil(ACC_Q16_MIN * SQRT2_UP) + 1  # the block's acc stays >= ACC_Q16_MIN


def motor_q16(v_um_s: int, sample_hz: int, per_sample: int, limit: int) -> int:
    """um/s (per_sample 1) or um/s^2 (per_sample 2) as Q16 per sample, floor, at most limit."""
    return min(int(v_um_s) * Q16 // sample_hz ** per_sample, limit)


def motor_problem(v_um_s: int, a_um_s2: int, sample_hz: int) -> str | None:
    """A motor's head-equivalent bound (um/s, um/s^2; 0: none) that the firmware cannot run."""
    if v_um_s and motor_q16(v_um_s, sample_hz, 1, SPEED_Q16_LIMIT) < MOTOR_V_Q16_MIN:
        return (f"lets the head move at most {v_um_s / 1000:g} mm/s along its worst direction, below the firmware's "
                f"least speed ({MOTOR_V_Q16_MIN} Q16 um/sample at {sample_hz} Hz); raise it")
    if a_um_s2 and motor_q16(a_um_s2, sample_hz, 2, ACC_Q16_LIMIT) < MOTOR_A_Q16_MIN:
        return (f"lets the head accelerate at most {a_um_s2 / 1000:g} mm/s^2 along its worst direction, below the "
                f"firmware's least acceleration ({MOTOR_A_Q16_MIN} Q16 um/sample^2 at {sample_hz} Hz); raise it")
    return None


def motion_ints(motion: dict) -> dict:
    """[motion] (mm units, defaults filled) as the firmware's integers, the one conversion."""
    return {"accel_um_s2": (um(motion["accel_x_mm_s2"]), um(motion["accel_y_mm_s2"])),
            "jdev_um": um(motion["junction_deviation_mm"]), "feed_um_min": um(motion["max_feed_mm_min"]),
            "sample_hz": int(motion["sample_hz"])}


def finite_problem(v: float) -> str | None:
    return None if math.isfinite(v) else f"must be a finite number, got {v}"


def scale_problem(scale: float) -> str | None:
    if SCALE_MIN <= scale <= SCALE_MAX:
        return None
    return f"must be in [1/65536, 256] (the firmware's Q16 scale), got {scale:g}"


def offset_problem(v: float) -> str | None:
    if abs(v) <= OFFSET_MM_MAX:
        return None
    return f"must be within +-{OFFSET_MM_MAX:g} (the largest machine), got {v:g}"


def seg_um_problem(seg_um: int) -> str | None:
    return None if SEG_UM_MIN <= seg_um <= SEG_UM_MAX else f"must be in [{SEG_UM_MIN}, {SEG_UM_MAX}] um, got {seg_um}"


S_MAX_RANGE = (1, 9999)  # S of full laser power (grbl's $30): duty = S * 255 / s_max in 32 bits
SERVO_DEG_RANGE = (0, 180)
M300_DOWN_RANGE = (0, 10000)  # M300 S (thousandths in the C: NNIK_GC_M300_DOWN = S * 1000, int32)


def int_range(lo: int, hi: int, unit: str = ""):
    """A check for an integer key: lo <= v <= hi."""
    return lambda v: None if lo <= v <= hi else f"must be in [{lo}, {hi}]{unit}, got {v}"


def tool_z_um_problem(z_um: int) -> str | None:
    return None if abs(z_um) <= TOOL_Z_UM_MAX else f"must be within +-{TOOL_Z_UM_MAX} um (+-1 m), got {z_um}"


def tool_z_problem(z_mm: float) -> str | None:
    if abs(z_mm) <= TOOL_Z_MM_MAX:
        return None
    return f"must be within +-{TOOL_Z_MM_MAX:g} mm, got {z_mm:g}"


SHAPER_RAM_BUDGET = 512  # bytes of SRAM the shaper's buffers may take on the ATmega328
# taps per axis (3hump_ei's five impulses, each split between the two samples around it); uint8 delays
SHAPER_MAX_TAPS, SHAPER_MAX_DELAY = 10, 255


def shaper_len(taps) -> int:
    """The shaper's memory in samples per axis (its longest delay); 0 without a shaper."""
    return max((max(d) for _, d in taps), default=0)


def shaper_ram_bytes(taps) -> int:
    """SRAM of the shaper (nnik_shaper.h): the int16 increments per axis, the running sums of X, Y
    and the tool's progress (int32), the ring's slot, the tool's planned duty and progress per
    sample, its 6 B of state and its two uint32 of path length."""
    length = shaper_len(taps)
    return 2 * 2 * length + 3 * 4 + 1 + 2 * length + 6 + 8 if length else 0


PROGRESS_SHIFT_MIN = 14  # the tool's progress unit is at finest 2^(16 - 14) = 1/4 um


def progress_shift(move_max_q16: int) -> int:
    """NNIK_SH_PSH: the tool's progress unit is 2^(PSH - 16) um, the finest (PSH >= 14) in which
    no sample's progress exceeds 255 (uint8 per sample), with every sample moving at most
    move_max_q16 (Q16 um): a sample's units are floor((fr + moved) / 2^PSH), fr < 2^PSH, so at
    most (2^PSH - 1 + move_max) >> PSH.  Then every window sum of the progress is at most
    255 * 255 < 2^16 (the lag and Q[n] - Q[m] fit uint16) and its S = sum A_i W_i at most
    2^15 (255 * 255) < 2^31 (int32): no overflow, whatever the speed."""
    shift = PROGRESS_SHIFT_MIN
    while ((1 << shift) - 1 + move_max_q16) >> shift > 255:
        shift += 1
    return shift


def shaper_problem(taps, feed_um_min: int, sample_hz: int) -> str | None:
    """Per axis (Q15 amplitudes, delays in samples): what the firmware's shaper cannot hold."""
    if len(taps) != 2:
        return "shaper taps: one (amplitudes, delays) per axis"
    for amps, delays in taps:
        if len(amps) != len(delays) or not 1 <= len(amps) <= SHAPER_MAX_TAPS or sum(amps) != 32768 or min(amps) < 0:
            return f"shaper amplitudes must be 1..{SHAPER_MAX_TAPS} Q15 taps summing to 32768"
        if min(delays) < 0 or max(delays) > SHAPER_MAX_DELAY:
            return (f"the shaper's delays must be 0..{SHAPER_MAX_DELAY} samples, got {max(delays)}: raise f_hz or "
                    "lower sample_hz")
    vmax_um = vn_q16(feed_um_min, sample_hz) // Q16 + 2
    if shaper_len(taps) * vmax_um >= 1 << 15:
        return (f"shaper too long for the max feed: its window sums would overflow int16 ({shaper_len(taps)} samples "
                f"at up to {vmax_um} um/sample); lower max_feed_mm_min or raise f_hz")
    if shaper_ram_bytes(taps) > SHAPER_RAM_BUDGET:
        return (f"shaper needs {shaper_ram_bytes(taps)} B of SRAM (> {SHAPER_RAM_BUDGET} B): its longest delay, "
                f"{shaper_len(taps)} samples, is too long; raise f or lower sample_hz")
    return None


# The planner's lookahead per chip (issue 26): grbl's 16 blocks where the G-code sketch's static RAM
# leaves STACK_RESERVE_BYTES for the stack (on the Uno: 12 blocks without a shaper, 8-9 with ZVD). The sketch's RAM (avr-size .data + .bss of the Uno's sender
# build, nnik.bench.plan_ram; tests/firmware/gcode/test_plan_depth.py checks the formula against the
# real build) is GCODE_RAM_BYTES, PLAN_BLOCK_BYTES per queued block, and the shaper's buffers plus
# SHAPER_CODE_RAM_BYTES when a shaper is built in. The IK's tables live in flash: the same on every IK.
PLAN_BLOCKS_MAX = 16
PLAN_BLOCK_BYTES = 44  # sizeof(nnik_pl_block_t) on AVR
GCODE_RAM_BYTES = 1004  # the sender build's static RAM less the queue and the shaper
SHAPER_CODE_RAM_BYTES = 10  # the shaper's own statics beside its buffers
# what the stack keeps: the 256 B at least, and the sketch's deepest stack on simavr, 510 B on
# every shipped job and build measured (nnik.bench.plan_ram; the test runs the circle job and checks it)
STACK_RESERVE_BYTES = max(256, 512)
MCU_RAM_BYTES = {"atmega328p": 2048, "atmega2560": 8192}


def gcode_ram_bytes(blocks: int, shaper_ram: int) -> int:
    """The G-code sketch's static RAM with that many planner blocks and shaper buffers (B)."""
    return GCODE_RAM_BYTES + PLAN_BLOCK_BYTES * blocks + (shaper_ram + SHAPER_CODE_RAM_BYTES if shaper_ram else 0)


def plan_blocks_for(mcu: str, shaper_ram: int) -> int:
    """The deepest lookahead (2..PLAN_BLOCKS_MAX) whose build leaves STACK_RESERVE_BYTES of the chip's RAM."""
    free = MCU_RAM_BYTES[mcu] - STACK_RESERVE_BYTES - gcode_ram_bytes(0, shaper_ram)
    return max(2, min(PLAN_BLOCKS_MAX, free // PLAN_BLOCK_BYTES))
