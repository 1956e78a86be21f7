"""``nnik job --check``: the job parsed and planned as the chip would (grbl's $C), without the IK
or the chip: the motion time, the tool-on length and the extent, from the planner's samples."""

from __future__ import annotations

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.interpreter import Interpreter
from nnik.firmware.gcode.planner import duty_of
from nnik.firmware.gcode.sampler import run_ops


def check_report(lines: list, cfg: MachineConfig) -> dict:
    it = Interpreter(cfg)
    for raw in lines:
        it.line(raw)
    st = run_ops(it.plan.ops, cfg)
    kind = np.asarray(st.kind, dtype=np.int64)
    planned = np.asarray(st.planned, dtype=np.float64).reshape(-1, 2)
    step = np.hypot(*np.diff(np.vstack([[0.0, 0.0], planned]), axis=0).T) if len(planned) else np.zeros(0)
    duty = duty_of(st) if len(kind) else np.zeros(0, np.int64)
    on = (duty != cfg.tool_off_duty) & (kind == 0)
    rest_ticks = np.asarray(st.rest_ticks, dtype=np.int64)
    seconds = float((kind == 0).sum() / cfg.sample_hz + rest_ticks.sum() / cfg.tick_hz)
    ends = np.asarray(it.plan.ends, dtype=np.int64).reshape(-1, 2)
    ext = ([float(v) / 1000 for v in ends.min(0)], [float(v) / 1000 for v in ends.max(0)]) if len(ends) else None
    return {"check": {"motion_s": seconds, "tool_on_mm": float(step[on].sum() / 1000.0),
                      "travel_mm": float(step[~on].sum() / 1000.0), "blocks": len(it.plan.ends),
                      "machine_extent_mm": ext}}
