"""What every kind of job is: a model directory read once and a request in, the figures out.

A kind composes the stages it needs, in their order (nnik/job/__init__.py draws them); the
stages never import a kind. The open-loop job (nnik.job.open_loop.OpenLoopJob: the pick's IK on
the firmware's samples) and the closed-loop job (nnik.job.closed_loop.ClosedLoopJob: a DC-servo
XY table's controller closing the loop on its motors) are the two there are. The closed loop
reuses parse and the interpreter and planner, and puts its own stages beside the open loop's:
reference (the planner's samples at the servo tick, in counts), servo_loop (the loop in Python
and on the chip), servo_measure and servo_report; its model directory is a servo_dir.ServoDir.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

from nnik.firmware.model_dir import ModelDir
from nnik.job.parse import JobRequest


class JobKind(ABC):
    """One kind of job: run(model, request) -> the job's figures (OUTDIR/job/JOB.json's)."""

    name: str

    @abstractmethod
    def run(self, model: ModelDir, request: JobRequest) -> dict:
        """Run the request on the model directory (read once, by the caller)."""
