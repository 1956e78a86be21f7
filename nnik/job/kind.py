"""What every kind of job is: a model directory read once and a request in, the figures out.

A kind composes the stages it needs, in their order (nnik/job/__init__.py draws them); the
stages never import a kind. The open-loop job (nnik.job.open_loop.OpenLoopJob: the pick's IK on
the firmware's samples) is the one there is. A closed-loop job (a controller closing the loop on
the motors instead of the open-loop IK) goes beside it as nnik/job/closed_loop.py: it reuses
parse, plan and shape as they are, puts its own stage module (e.g. nnik/job/control.py, taking a
ShapedJob and giving the SampledJob that measure reads) where `sample` is, and its own
co-simulation if its firmware differs; measure and report stay as they are. None of the stages it
does not share needs to change.
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
