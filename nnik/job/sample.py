"""Stage 4 of a job, sample and IK (open loop): the plan through the planner's velocity profile,
the fixed-rate sampler and the shaper, as the chip runs them (nnik.firmware.gcode.sampler), every
shaped sample through the pick's IK, and each sample into a stepper segment and its steps.

ShapedJob + the model directory's IK -> SampledJob: the segments and every step event (segment,
tick, motor, direction) the chip must emit. A closed-loop job replaces this stage (a controller
instead of the open-loop IK) and hands the same SampledJob on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.firmware.gcode.motion import Segments, plan_steps
from nnik.firmware.gcode.steps import model_events
from nnik.firmware.ik_oracle import IkFn
from nnik.job.shape import ShapedJob


@dataclass
class SampledJob:
    shaped: ShapedJob
    segments: Segments
    events: np.ndarray  # (E, 4) segment, tick, motor, direction (nnik.firmware.gcode.steps)

    @property
    def seconds(self) -> float:
        """The job's planned time."""
        return float(self.segments.ticks.sum() / self.shaped.cfg.tick_hz)


def sample(shaped: ShapedJob, ik: IkFn) -> SampledJob:
    seg = plan_steps(shaped.plan, shaped.cfg, ik)
    return SampledJob(shaped, seg, model_events(seg))
