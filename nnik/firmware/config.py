"""The G-code firmware's machine settings (what nnik_gcode_config.h fixes), shared by the
Arduino export and the Python model of the firmware.

Motion (issue 18): per-axis acceleration (um/s^2), junction deviation (um), max feed (um/min:
it caps F and is the G0 speed), the sample rate of the planned trajectory (it must divide the
tick rate) and the input shaper (kind and, per axis, Q15 amplitudes summing to 32768 at delays
in whole samples, from nnik.dynamics.shapers). The firmware's integer forms are properties:
acc_q16 (um/sample^2 * 65536, floor), vn_max_q16 (um/sample * 65536 at max feed, floor)."""

from __future__ import annotations

from dataclasses import dataclass
from math import isqrt

from nnik.dynamics.shapers import KINDS, design, quantize

TOOLS = ("laser", "pen", "servo", "spindle", "knife", "none")
# how a job turns the tool on: "s" (M3/M4 with S: a laser; on a pen-like tool, down while on),
# "z" (down at or below pen_z_um), "e" (Marlin: a move that extrudes), "m300" (a servo pen:
# M300 S at or below m300_down_max is down), "none" (never on)
RULES = ("s", "z", "e", "m300", "none")
FEATURES = frozenset({"g5", "g93", "planes", "wcs"})
# the Uno's default build: grbl's own coordinate systems and planes; G93 (1.1 kB) and G5 (2.2 kB) are
# left out (each line that needs one: error 20), as grbl's config.h leaves out what does not fit;
# a job's build carries exactly what its file uses, and the ATmega2560 build carries everything
UNO_FEATURES = frozenset({"wcs", "planes"})
SHAPER_KINDS = ("none",) + KINDS
SERVO_MIN_US, SERVO_MAX_US = 544, 2400  # 0 and 180 degrees, as Arduino's Servo library
SERVO_US_PER_COUNT = 64  # Timer2 at 16 MHz / 1024: 61 Hz, 64 us per count

from nnik.machine import ranges
from nnik.machine.domain import domain_um
from nnik.machine.motor_limits import KEYS as MOTOR_KEYS
from nnik.machine.motor_limits import motor_rows
from nnik.machine.ranges import Q16 as SCALE_ONE


@dataclass(frozen=True)
class MachineConfig:
    """What nnik_gcode_config.h fixes: work origin (machine um of program (0, 0)), segment
    length, tick rate, rapid and default feed (um/min)."""

    origin_um: tuple[int, int]
    seg_um: int = 500  # longest arc chord
    tick_hz: int = 10_000
    max_feed_um_min: int = 3_000_000  # caps F; G0 and G28 move at it
    feed_um_min: int = 600_000
    # the tool on D11 (OC2A, Timer2; grbl's spindle PWM pin): "laser" (M3/M4/M5 with S; duty =
    # S * 255 / s_max, grbl's $30), "pen" (Z > pen_z_um: D11 low, pen up; else high, down) or
    # "servo" (the same Z threshold, a servo pulse of servo_up_deg / servo_down_deg at 61 Hz)
    tool: str = "laser"
    s_max: int = 1000
    pen_z_um: int = 0
    servo_up_deg: int = 90
    servo_down_deg: int = 30
    accel_um_s2: tuple[int, int] = (1_000_000, 1_000_000)
    junction_dev_um: int = 10
    sample_hz: int = 1000
    shaper: str = "none"  # a kind (both axes), or "x/y" kinds per axis (a [shaper] table)
    # per axis (amplitudes Q15, delays in samples); empty with shaper "none"
    shaper_taps: tuple = ()
    # per axis (kind, f_hz, zeta) the taps were designed from (their Klipper figures); may be empty
    shaper_design: tuple = ()
    # the planner's lookahead queue; 0: the deepest the chip's RAM holds (ranges.plan_blocks_for: 16
    # on the Mega, on the Uno what leaves 256 B for the stack beside the shaper): read cfg.lookahead
    plan_blocks: int = 0
    # an arc (G2/G3 in G17) planned as one block, cut into chords by the sampler
    # (nnik.firmware.gcode.planner_arc); the chip does not do it yet: False for every export
    arc_blocks: bool = False
    # the sampler's rule: True, the G-code firmware's (nnik_plan_sample.c: when speed + acc may not go,
    # the fastest between the speed that may go and the one that may not, 4 halvings; the brake
    # test's credit brake_alpha_q16; block ends passed at most at the junction's limit); False, the
    # rule before both (hold, else speed - acc; no credit; block ends at most at their exit), kept by
    # the closed-loop reference (nnik.job.reference) whose tuned gains and pretrained controllers
    # were measured on it
    speed_search: bool = True
    mcu: str = "atmega328p"  # the chip the firmware is built for (avr-gcc's -mmcu)
    rule: str = ""  # the tool rule (RULES); "" = the tool's default: s for a laser, else z
    marlin: bool = False  # G4 P in ms, Marlin's setup G codes noted, E words read
    m300_down_max: int = 40  # M300 S at or below this puts a servo pen down (unicorn: 30 down, 50 up)
    scale_q16: int = SCALE_ONE  # the job's frame -> the machine's: p * scale / 2^16 + shift_um
    shift_um: tuple[int, int] = (0, 0)
    # soft limits, um (machine less the work origin): ((x_lo, y_lo), (x_hi, y_hi)); None: none
    bounds_um: tuple | None = None
    # build options, as grbl's config.h: g5 (Marlin's Bezier), g93 (inverse time), planes (arcs in
    # G18/G19), wcs (G10, G55-G59, G28.1, G30.1); a line that needs one left out is error 20
    features: frozenset = FEATURES
    # motor limits after the IK (nnik.machine.motor_limits.motor_rows): per motor (cx, cy, d Q15,
    # head-equivalent v um/s, a um/s^2; 0: none) and the head's speed cap vc um/s (0: none); () without
    motor_rows: tuple = ()
    motor_vc_um_s: int = 0

    @property
    def motor_q16(self) -> tuple:
        """Per motor (cx, cy, d, v, a) with v, a as Q16 per sample (0: none), and vc Q16 (0: none)."""
        lim = ranges.SPEED_Q16_LIMIT, ranges.ACC_Q16_LIMIT
        rows = tuple((cx, cy, d, *(ranges.motor_q16(x, self.sample_hz, k + 1, lim[k]) if x else 0 for k, x in enumerate((v, a))))
                     for cx, cy, d, v, a in self.motor_rows)
        return rows, ranges.motor_q16(self.motor_vc_um_s, self.sample_hz, 1, ranges.SPEED_Q16_LIMIT)

    @property
    def brake_credit(self) -> bool:
        """The G-code firmware's sampler rule (the brake test's credit, block ends passed at most at
        the junction's limit): not the closed-loop reference's (speed_search False) nor whole-arc
        blocks' (planner_arc: their acc may be under twice the credit), which keep the rule before."""
        return self.speed_search and not self.arc_blocks

    @property
    def brake_alpha_q16(self) -> int:
        """The sampler's brake test credit (nnik_plan.h NNIK_PL_ALPHA, Q16 um/sample^2): half the
        least acceleration any block may get (an axis' limit, or a motor's after the IK: a block
        along u has acc >= A 2^15 / (|c . u| + d + 1) >= A 2^15 / (ceil|c| + d + 1)), so that it is
        at most half of every block's acc; 0 for the closed-loop reference's rule (speed_search
        False) and for whole-arc blocks (planner_arc: their acc may be less)."""
        if not self.brake_credit:
            return 0
        least = min(self.acc_q16)
        if self.motor_rows:
            for cx, cy, d, _, a in self.motor_q16[0]:
                if a:
                    n = isqrt(cx * cx + cy * cy) + 1 + d + 1
                    least = min(least, max((a << 15) // n - 1, 0))
        return least >> 1

    @property
    def rapid_um_min(self) -> int:
        return self.max_feed_um_min

    @property
    def acc_q16(self) -> tuple[int, int]:
        return tuple(ranges.acc_q16(a, self.sample_hz) for a in self.accel_um_s2)

    @property
    def vn_max_q16(self) -> int:
        return ranges.vn_q16(self.max_feed_um_min, self.sample_hz)

    @property
    def sample_ticks(self) -> int:
        return self.tick_hz // self.sample_hz

    @property
    def shaper_len(self) -> int:
        """The shaper's memory in samples per axis (its longest delay); 0 without a shaper."""
        return ranges.shaper_len(self.shaper_taps)

    @property
    def progress_shift(self) -> int:
        """NNIK_SH_PSH (nnik.machine.ranges.progress_shift): a sample moves at most the fastest
        feed, or the sampler's floor (a block's acceleration / 4 <= sqrt(2) a_axis / 4)."""
        return ranges.progress_shift(max(self.vn_max_q16, *self.acc_q16, 1))

    @property
    def lookahead(self) -> int:
        """The planner's queue in blocks: plan_blocks, or the chip's default depth."""
        return self.plan_blocks or ranges.plan_blocks_for(self.mcu, self.shaper_ram_bytes)

    @property
    def shaper_ram_bytes(self) -> int:
        """SRAM of the shaper's buffers: int16 increments and int16 window sums per axis."""
        return ranges.shaper_ram_bytes(self.shaper_taps)

    def __post_init__(self):
        if ranges.seg_um_problem(self.seg_um):
            raise ValueError(f"segment length {ranges.seg_um_problem(self.seg_um)}")
        if self.tick_hz > 12_000:
            raise ValueError("tick rate above 12 kHz overflows the 32-bit tick count")
        if self.tool not in TOOLS:
            raise ValueError(f"tool must be one of {', '.join(TOOLS)}")
        if ranges.int_range(*ranges.S_MAX_RANGE)(self.s_max):
            raise ValueError(f"s_max {ranges.int_range(*ranges.S_MAX_RANGE)(self.s_max)}")
        if any(ranges.int_range(*ranges.SERVO_DEG_RANGE)(d) for d in (self.servo_up_deg, self.servo_down_deg)):
            raise ValueError("servo angles must be 0..180 degrees")
        if ranges.int_range(*ranges.M300_DOWN_RANGE)(self.m300_down_max):
            raise ValueError(f"m300_down_max {ranges.int_range(*ranges.M300_DOWN_RANGE)(self.m300_down_max)}")
        if self.rule not in RULES + ("",):
            raise ValueError(f"tool rule must be one of {', '.join(RULES)}")
        if self.tool == "laser" and self.rule == "z":
            raise ValueError("a laser takes S, not Z: Z is its focus")
        if not set(self.features) <= FEATURES:
            raise ValueError(f"build options must be among {', '.join(sorted(FEATURES))}")
        if not ranges.SCALE_Q16_MIN <= self.scale_q16 <= ranges.SCALE_Q16_MAX:
            raise ValueError("scale must be 1/65536..256")
        if ranges.tool_z_um_problem(self.pen_z_um):
            raise ValueError(f"the tool's Z threshold {ranges.tool_z_um_problem(self.pen_z_um)}")
        self._check_motion()

    @property
    def tool_rule(self) -> str:
        return self.rule or ("s" if self.tool == "laser" else "z")

    @property
    def pen_like(self) -> bool:
        return self.tool != "laser"

    @property
    def z_home_um(self) -> int:
        """Z of G28/G30 until G28.1/G30.1 store one: 5 mm above the tool-down threshold."""
        return self.pen_z_um + 5000

    def _check_motion(self) -> None:
        """The firmware's integer ranges (nnik.machine.ranges, the scenario check's too)."""
        if len(self.accel_um_s2) != 2:
            raise ValueError("acceleration: one per axis")
        for key, problem in ranges.motion_problems(self.accel_um_s2, self.junction_dev_um, self.max_feed_um_min,
                                                   self.sample_hz):
            raise ValueError(f"[motion] {key}: {problem}")
        if self.arc_blocks and self.motor_rows:
            raise ValueError("arc blocks (a study of the model) do not apply motor limits: not both")
        if self.shaper.count("/") > 1 or any(k not in SHAPER_KINDS for k in self.shaper.split("/")):
            raise ValueError(f"shaper must be one of {', '.join(SHAPER_KINDS)}, or X/Y: one per axis")
        if (self.shaper == "none") != (not self.shaper_taps):
            raise ValueError("shaper taps are needed with a shaper, and none without")
        problem = ranges.shaper_problem(self.shaper_taps, self.max_feed_um_min, self.sample_hz) if self.shaper_taps else None
        if problem:
            raise ValueError(problem)
        if self.plan_blocks and not 2 <= self.plan_blocks <= 64:
            raise ValueError("planner queue must be 2..64 blocks")
        for cx, cy, d, v, a in self.motor_rows:
            if ranges.motor_problem(v, a, self.sample_hz) or max(abs(cx), abs(cy)) + d > ranges.MOTOR_Q15 + 2:
                raise ValueError(f"motor limits: {ranges.motor_problem(v, a, self.sample_hz) or 'row out of Q15'}")
        if self.mcu not in ranges.MCU_RAM_BYTES:
            raise ValueError(f"unknown MCU {self.mcu!r}; known: {', '.join(ranges.MCU_RAM_BYTES)}")

    def pen_duty(self, down: bool) -> int:
        """OCR2A of the pen up or down (pen: 0 / 255; servo: the pulse in 64 us counts)."""
        if self.tool == "none":
            return 0
        if self.tool != "servo":
            return 255 if down else 0
        deg = self.servo_down_deg if down else self.servo_up_deg
        return (SERVO_MIN_US + deg * (SERVO_MAX_US - SERVO_MIN_US) // 180) // SERVO_US_PER_COUNT

    @property
    def tool_off_duty(self) -> int:
        """The duty with the tool off: laser off, or the pen up."""
        return 0 if self.tool == "laser" else self.pen_duty(False)

    def defines(self) -> dict[str, str]:
        """The macros of nnik_gcode_config.h: the tool's and the motion's (its #ifndef defaults
        are this class's; a build may pass them as -D)."""
        return {**self.tool_defines(), **self.motion_defines()}

    def motion_defines(self) -> dict[str, str]:
        if not self.speed_search:
            raise ValueError("the chip's sampler always searches (speed_search is the closed-loop reference's)")
        ax, ay = self.acc_q16
        out = {"NNIK_GC_SAMPLE_HZ": f"{self.sample_hz}UL", "NNIK_GC_ACC_X": f"{ax}UL", "NNIK_GC_ACC_Y": f"{ay}UL",
               "NNIK_GC_JDEV_UM": f"{self.junction_dev_um}UL", "NNIK_GC_MAX_FEED_UM_MIN": f"{self.max_feed_um_min}L",
               "NNIK_PL_N": str(self.lookahead), "NNIK_PL_ALPHA": f"{self.brake_alpha_q16}UL",
               "NNIK_SH_LEN": str(self.shaper_len)}
        out.update(self.motor_defines())
        if self.shaper_taps:
            n = max(len(a) for a, _ in self.shaper_taps)
            pad = [(list(a) + [0] * (n - len(a)), list(d) + [0] * (n - len(d))) for a, d in self.shaper_taps]
            out["NNIK_SH_N"] = str(n)
            out["NNIK_SH_AMPS"] = "{" + ",".join("{" + ",".join(map(str, a)) + "}" for a, _ in pad) + "}"
            out["NNIK_SH_DELAYS"] = "{" + ",".join("{" + ",".join(map(str, d)) + "}" for _, d in pad) + "}"
            out["NNIK_SH_SAME"] = str(int(pad[0] == pad[1]))
            out["NNIK_SH_PSH"] = str(self.progress_shift)
        return out

    def motor_defines(self) -> dict[str, str]:
        """nnik_plan.c motor_caps()'s constants; none without motor limits (the C as before)."""
        if not self.motor_rows:
            return {}
        rows, vc = self.motor_q16
        out = {"NNIK_GC_MOTOR": "1", "NNIK_GC_MOTOR_V": str(int(any(r[3] for r in rows))),
               "NNIK_GC_MOTOR_A": str(int(any(r[4] for r in rows))), "NNIK_GC_MOTOR_VC": f"{vc}UL"}
        for i, (cx, cy, d, v, a) in enumerate(rows):
            out.update({f"NNIK_GC_M{i}_CX": f"{cx}L", f"NNIK_GC_M{i}_CY": f"{cy}L", f"NNIK_GC_M{i}_D": f"{d}UL",
                        f"NNIK_GC_M{i}_V": f"{v or 0xFFFFFFFF}UL", f"NNIK_GC_M{i}_A": f"{a or 0xFFFFFFFF}UL"})
        return out

    def tool_defines(self) -> dict[str, str]:
        pen = self.tool != "laser"
        out = {"NNIK_GC_TOOL": "1" if pen else "0", "NNIK_GC_S_MAX": f"{self.s_max}L",
                "NNIK_GC_PEN_Z_UM": f"{self.pen_z_um}L",
                "NNIK_GC_PEN_UP_DUTY": str(self.pen_duty(False) if pen else 0),
                "NNIK_GC_PEN_DOWN_DUTY": str(self.pen_duty(True) if pen else 0),
                "NNIK_GC_TOOL_CS": "7" if self.tool == "servo" else "4",
                "NNIK_GC_RULE": str(RULES.index(self.tool_rule)), "NNIK_GC_MARLIN": str(int(self.marlin)),
                "NNIK_GC_M300_DOWN": f"{self.m300_down_max * 1000}L",
                **{f"NNIK_GC_{f.upper()}": str(int(f in self.features)) for f in sorted(FEATURES)}}
        framed = self.scale_q16 != SCALE_ONE or any(self.shift_um)
        out.update({"NNIK_GC_FRAME": str(int(framed)), "NNIK_GC_SCALE_Q16": f"{self.scale_q16}L",
                    "NNIK_GC_SHIFT_X_UM": f"{self.shift_um[0]}L", "NNIK_GC_SHIFT_Y_UM": f"{self.shift_um[1]}L"})
        (x0, y0), (x1, y1) = self.bounds_um if self.bounds_um is not None else ((0, 0), (0, 0))
        out.update({"NNIK_GC_SOFT_LIMITS": str(int(self.bounds_um is not None)), "NNIK_GC_MIN_X_UM": f"{x0}L",
                    "NNIK_GC_MIN_Y_UM": f"{y0}L", "NNIK_GC_MAX_X_UM": f"{x1}L", "NNIK_GC_MAX_Y_UM": f"{y1}L"})
        return out


def default_machine(scn, shaper: str | None = None) -> MachineConfig:
    """Program (0, 0) at the centre of the workspace, 0.5 mm arc chords, 10 kHz ticks, the
    scenario's [tool] (a laser by default) and [motion] / [dynamics] (the shaper designed for the
    [dynamics] resonance per axis; shaper overrides [motion] shaper). ValueError: one line."""
    lo, hi = domain_um(scn.workspace)
    tool = dict(getattr(scn, "tool", None) or {})
    kind = tool.pop("kind", "laser")
    mo = dict(getattr(scn, "motion", None) or {})
    dyn = getattr(scn, "dynamics", None)
    sample_hz = int(mo.get("sample_hz", 1000))
    sh = shaper or mo.get("shaper", "none")
    if sh == "auto":
        raise ValueError("shaper 'auto' is not available yet (it picks by contour error: the lead's part of issue 18)")
    taps, designs = axis_shapers(sh, dyn, getattr(scn, "shaper", None), sample_hz)
    from nnik.machine.motion import MOTION

    ints = ranges.motion_ints({**{k: p.default for k, p in MOTION.items()}, **mo, "sample_hz": sample_hz})
    origin = tuple(int(v) for v in (lo + hi) // 2)
    bounds = tuple(tuple(int(v) - o for v, o in zip(e, origin)) for e in (lo, hi))
    rows, vc = motor_rows(scn.mechanism, scn.actuator, scn.workspace, {**mo, "sample_hz": sample_hz}, scn.source) \
        if any(mo.get(k) is not None for k in MOTOR_KEYS) else ((), 0)
    return MachineConfig(origin_um=origin, tool=kind, bounds_um=bounds, features=UNO_FEATURES,
                         accel_um_s2=ints["accel_um_s2"], junction_dev_um=ints["jdev_um"],
                         max_feed_um_min=ints["feed_um_min"],
                         sample_hz=sample_hz, shaper=sh, shaper_taps=taps, shaper_design=designs,
                         motor_rows=rows, motor_vc_um_s=vc, **tool)


def shaper_taps(kind: str, dynamics: dict | None, sample_hz: int) -> tuple:
    """Per axis (Q15 amplitudes, delays in samples) of the shaper kind for the [dynamics]
    resonance (nnik.dynamics.shapers.design, then quantize)."""
    return axis_shapers(kind, dynamics, None, sample_hz)[0]


def axis_shapers(name: str, dynamics: dict | None, table: dict | None, sample_hz: int) -> tuple[tuple, tuple]:
    """(taps, designs) per axis of the machine's shaper name: "none"; the [shaper] table's label
    (its type, frequency and damping ratio per axis); or a kind designed for the [dynamics]
    resonance (without [dynamics], at the [shaper] table's frequencies and damping ratios).
    An unshaped axis of a shaped machine passes its samples through (one tap of 1 at delay 0)."""
    if name == "none":
        return (), ()
    if table and name == table["label"]:
        designs = tuple(zip(table["type"], table["freq_hz"], table["damping"]))
    elif dynamics:
        designs = tuple((name, float(f), float(z)) for f, z in zip(dynamics["f_hz"], dynamics["zeta"]))
    elif table:
        designs = tuple((name if t != "none" else "none", f, z) for t, f, z in zip(table["type"], table["freq_hz"], table["damping"]))
    else:
        raise ValueError(f"shaper {name!r} needs a [dynamics] table (f_hz, zeta)")
    taps = []
    for kind, f, z in designs:
        amps, delays = ((1 << 15,), (0,)) if kind == "none" else quantize(design(kind, float(f), float(z)), sample_hz)
        taps.append((tuple(int(a) for a in amps), tuple(int(d) for d in delays)))
    return tuple(taps), designs
