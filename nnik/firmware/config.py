"""The G-code firmware's machine settings (what nnik_gcode_config.h fixes), shared by the
Arduino export and the Python model of the firmware."""

from __future__ import annotations

from dataclasses import dataclass

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

    def __post_init__(self):
        if not 100 <= self.seg_um <= 5000:
            raise ValueError("segment length must be 100..5000 um")
        if self.tick_hz > 12_000:
            raise ValueError("tick rate above 12 kHz overflows the 32-bit tick count")


def default_machine(scn) -> MachineConfig:
    """Program (0, 0) at the centre of the workspace, 0.5 mm segments, 10 kHz ticks."""
    lo, hi = domain_um(scn.workspace)
    return MachineConfig(origin_um=tuple(int(v) for v in (lo + hi) // 2))
