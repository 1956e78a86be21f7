"""Stage 3 of a job, shape: how the job fights the belts' vibration, decided before the chip's
build (its shaper taps are compiled in).

PlannedJob -> ShapedJob: the machine configuration and lines the chip runs and their plan.
Without a [dynamics] table the job runs as parsed (with the scenario's or --shaper's shaper,
already in the configuration). With one, every method (none, each input shaper, the job
precompensated offline) runs through the firmware's model on the tip
(nnik.firmware.gcode.compensation) and the one asked for, or auto's pick, is taken; its figures
and picture (OUTDIR/job/JOB_dynamics.png, and JOB_precompensated.gcode) come with it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from nnik.errors import NnikError
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.program import Plan
from nnik.firmware.ik_oracle import IkFn
from nnik.job.plan import PlannedJob, interpret


@dataclass
class ShapedJob:
    planned: PlannedJob
    cfg: MachineConfig  # the machine the chip runs: the chosen shaper's taps included
    lines: list[str]  # what the chip is sent (the precompensated job, if chosen)
    plan: Plan  # the interpreter's plan of lines on cfg
    dynamics: dict | None = None  # every method's figures and the pick (None: no [dynamics] table)

    @property
    def parsed(self):
        return self.planned.parsed


def _same_plan(a: MachineConfig, b: MachineConfig) -> bool:
    """The interpreter reads no shaper setting: a and b differ at most in the shaper."""
    return replace(a, shaper=b.shaper, shaper_taps=b.shaper_taps, shaper_design=b.shaper_design) == b


def shape(planned: PlannedJob, ik: IkFn, out_dir: Path) -> ShapedJob:
    parsed = planned.parsed
    scn, req = parsed.scenario, parsed.request
    if not scn.dynamics:
        return ShapedJob(planned, parsed.cfg, parsed.lines, planned.plan)
    from nnik.firmware.gcode.compensation import job_dynamics

    try:
        cfg, lines, dyn_fig, _ = job_dynamics(scn, parsed.cfg, parsed.lines, ik, parsed.asked, req.precompensate,
                                              req.source, out_dir, req.job.stem)
    except ValueError as exc:
        raise NnikError(str(exc), req.source) from None
    if lines is parsed.lines and _same_plan(cfg, parsed.cfg):
        return ShapedJob(planned, cfg, lines, planned.plan, dyn_fig)
    return ShapedJob(planned, cfg, lines, interpret(lines, cfg, req.source, None), dyn_fig)
