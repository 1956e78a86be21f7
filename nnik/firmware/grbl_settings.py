"""grbl 1.1's `$$` list for a build: what the chip answers, from the machine's configuration.

The settings are compiled in (the planner, the shaper and the trained IK are built and checked
for them): `$N=V` is accepted only with the value listed here. Settings grbl has that mean
nothing here (homing, limit pins, the Z axis of a two-axis machine) take grbl's defaults, and
docs/grbl_interface.md says which.
"""

from __future__ import annotations

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.machine.domain import domain_um

# grbl 1.1h's defaults for what this firmware does not have (homing, limit switches, Z)
HOMING = {22: "0", 23: "0", 24: "25.000", 25: "500.000", 26: "250", 27: "1.000"}
Z_AXIS = {102: "250.000", 112: "500.000", 122: "10.000", 132: "200.000"}


def _mm(um: float) -> str:
    return f"{um / 1000:.3f}"


def steps_per_mm(ik, origin_um) -> tuple[float, float]:
    """Per axis, the larger motor's steps for 1 mm from the work origin (a nonlinear machine's
    figure there: grbl's $100/$101)."""
    o = np.asarray(origin_um, dtype=np.int64)
    pts = np.stack([o, o + [1000, 0], o + [0, 1000]])
    out, _ = ik(pts)
    out = np.asarray(out, dtype=np.int64)
    return tuple(float(np.abs(out[k] - out[0]).max()) for k in (1, 2))


def grbl_settings(machine: MachineConfig, workspace, ik, soft_limits: bool = False) -> list[tuple[int, str]]:
    """[(number, value text)] in grbl's order."""
    lo, hi = domain_um(workspace)
    spm = steps_per_mm(ik, machine.origin_um)
    out = {0: str(1_000_000 // machine.tick_hz),  # a STEP pulse lasts one tick
           1: "255",  # the drivers stay enabled
           2: "0", 3: "0", 4: "0", 5: "0", 6: "0",
           10: "3",  # MPos and the buffer state in every status report
           11: _mm(machine.junction_dev_um),
           12: _mm(machine.seg_um),  # nnik's arc setting is the longest chord, not a deviation
           13: "0",
           20: "1" if soft_limits else "0", 21: "0",
           **HOMING,
           30: str(machine.s_max), 31: "0", 32: "1" if machine.tool == "laser" else "0",
           100: f"{spm[0]:.3f}", 101: f"{spm[1]:.3f}",
           110: _mm(machine.max_feed_um_min), 111: _mm(machine.max_feed_um_min),
           120: _mm(machine.accel_um_s2[0]), 121: _mm(machine.accel_um_s2[1]),
           130: _mm(int(hi[0] - lo[0])), 131: _mm(int(hi[1] - lo[1])),
           **Z_AXIS}
    return sorted(out.items())


def settings_c_string(settings: list[tuple[int, str]]) -> str:
    """The `$$` answer as one C string literal, a line per setting."""
    return '"' + "".join(f"${n}={v}\\n" for n, v in settings) + '"'
