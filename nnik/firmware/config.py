"""The G-code firmware's machine settings (what nnik_gcode_config.h fixes), shared by the
Arduino export and the Python model of the firmware."""

from __future__ import annotations

from dataclasses import dataclass

TOOLS = ("laser", "pen", "servo")
SERVO_MIN_US, SERVO_MAX_US = 544, 2400  # 0 and 180 degrees, as Arduino's Servo library
SERVO_US_PER_COUNT = 64  # Timer2 at 16 MHz / 1024: 61 Hz, 64 us per count

from nnik.machine.domain import domain_um


@dataclass(frozen=True)
class MachineConfig:
    """What nnik_gcode_config.h fixes: work origin (machine um of program (0, 0)), segment
    length, tick rate, rapid and default feed (um/min)."""

    origin_um: tuple[int, int]
    seg_um: int = 500
    tick_hz: int = 10_000
    rapid_um_min: int = 3_000_000
    feed_um_min: int = 600_000
    # the tool on D11 (OC2A, Timer2; grbl's spindle PWM pin): "laser" (M3/M4/M5 with S; duty =
    # S * 255 / s_max, grbl's $30), "pen" (Z > pen_z_um: D11 low, pen up; else high, down) or
    # "servo" (the same Z threshold, a servo pulse of servo_up_deg / servo_down_deg at 61 Hz)
    tool: str = "laser"
    s_max: int = 1000
    pen_z_um: int = 0
    servo_up_deg: int = 90
    servo_down_deg: int = 30

    def __post_init__(self):
        if not 100 <= self.seg_um <= 5000:
            raise ValueError("segment length must be 100..5000 um")
        if self.tick_hz > 12_000:
            raise ValueError("tick rate above 12 kHz overflows the 32-bit tick count")
        if self.tool not in TOOLS:
            raise ValueError(f"tool must be one of {', '.join(TOOLS)}")
        if not 1 <= self.s_max <= 9999:
            raise ValueError("s_max must be 1..9999")
        if not (0 <= self.servo_up_deg <= 180 and 0 <= self.servo_down_deg <= 180):
            raise ValueError("servo angles must be 0..180 degrees")

    def pen_duty(self, down: bool) -> int:
        """OCR2A of the pen up or down (pen: 0 / 255; servo: the pulse in 64 us counts)."""
        if self.tool == "pen":
            return 255 if down else 0
        deg = self.servo_down_deg if down else self.servo_up_deg
        return (SERVO_MIN_US + deg * (SERVO_MAX_US - SERVO_MIN_US) // 180) // SERVO_US_PER_COUNT

    @property
    def tool_off_duty(self) -> int:
        """The duty with the tool off: laser off, or the pen up."""
        return 0 if self.tool == "laser" else self.pen_duty(False)

    def defines(self) -> dict[str, str]:
        """The tool's macros of nnik_gcode_config.h (its #ifndef defaults are this class's)."""
        pen = self.tool != "laser"
        return {"NNIK_GC_TOOL": "1" if pen else "0", "NNIK_GC_S_MAX": f"{self.s_max}L",
                "NNIK_GC_PEN_Z_UM": f"{self.pen_z_um}L",
                "NNIK_GC_PEN_UP_DUTY": str(self.pen_duty(False) if pen else 0),
                "NNIK_GC_PEN_DOWN_DUTY": str(self.pen_duty(True) if pen else 0),
                "NNIK_GC_TOOL_CS": "7" if self.tool == "servo" else "4"}


def default_machine(scn) -> MachineConfig:
    """Program (0, 0) at the centre of the workspace, 0.5 mm segments, 10 kHz ticks, and the
    scenario's [tool] (a laser by default)."""
    lo, hi = domain_um(scn.workspace)
    tool = dict(getattr(scn, "tool", None) or {})
    kind = tool.pop("kind", "laser")
    return MachineConfig(origin_um=tuple(int(v) for v in (lo + hi) // 2), tool=kind, **tool)
