"""The stepper interrupt's DDA is 16-bit (gcode.ino.j2): a sample that moves a motor more than
MAX_SEGMENT_STEPS steps is refused by the model with one line, never stepped wrongly."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.motion import MAX_SEGMENT_STEPS, interpret, plan_steps

LINES = ["G21 G90", "G1 X5 Y0 F3000"]


def scaled_ik(steps_per_um: int):
    return lambda p: (np.asarray(p, np.int64) * steps_per_um, np.zeros(len(p), np.int64))


def test_a_sample_of_more_steps_than_the_dda_holds_is_one_error():
    cfg = MachineConfig(origin_um=(0, 0), tool="laser", sample_hz=1000)
    plan = interpret(LINES, cfg)
    seg = plan_steps(plan, cfg, scaled_ik(1))
    largest = int(np.abs(seg.delta).max())
    assert 0 < largest <= MAX_SEGMENT_STEPS
    k = MAX_SEGMENT_STEPS // largest + 1  # the same motion with k times the steps: over the limit
    with pytest.raises(NnikError, match=f"more than the stepper's {MAX_SEGMENT_STEPS}"):
        plan_steps(interpret(LINES, cfg), cfg, scaled_ik(k))
