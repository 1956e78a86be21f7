"""The closed-loop job (`nnik job OUTDIR JOB.gcode` on a dc_servo xy_table): a controller closes
the loop on the motors, following the G-code's reference.

parse and plan (nnik.job.reference: the open-loop machines' interpreter and planner, sampled at the
servo tick; ;@step raw steps; G4 holds) -> the reference per tick in counts -> the loop
(nnik.job.servo_loop: the controller's integer model against the scenario's plant in Python, and
its C on the simulated Uno, chip = model tick by tick) -> measure (nnik.job.servo_measure: contour
error to the path, tracking error, steps, reversals, saturation) -> report (servo_report: JSON and
PNG in OUTDIR/job/). The model directory is a nnik.job.servo_dir.ServoDir, not the IK's ModelDir.
"""

from __future__ import annotations

from dataclasses import dataclass

from nnik.files.outdir import JOB_DIR
from nnik.job.kind import JobKind
from nnik.job.parse import JobRequest
from nnik.job.reference import job_reference
from nnik.job.servo_dir import ServoDir
from nnik.job.servo_loop import loop
from nnik.job.servo_measure import measure
from nnik.job.servo_report import picture, write


@dataclass
class ClosedLoopJob(JobKind):
    """controller: pid, pdff, ccc, nn_axes or nn_vector (None: the run's chosen one); use_chip None: on the simulated
    Uno when the toolchain is there; check: parse and plan only (the reference), nothing written."""

    controller: str | None = None
    use_chip: bool | None = None
    check: bool = False
    tag: str | None = None  # the files are OUTDIR/job/JOB_TAG.json and .png (nnik run: the controller)
    name = "closed loop"

    def run(self, model: ServoDir, request: JobRequest) -> dict:
        parsed, ref = job_reference(request)
        scn = request.scenario
        head = {"scenario": scn.name, "job": request.job.name, "kind": "closed loop", "gcode": parsed.summary,
                "reference": {"ticks": len(ref.counts), "seconds": ref.seconds, "steps": len(ref.step_ticks),
                              "tick_s": ref.tick_s}}
        if self.check:
            return head
        kind = self.controller or model.chosen
        ctl = model.controller(kind)
        out = model.path / JOB_DIR
        out.mkdir(parents=True, exist_ok=True)
        looped = loop(ref, scn.servo, ctl, out / "work" / request.job.stem, self.use_chip)
        figures, contour = measure(ref, looped.trace)
        stem = request.job.stem + (f"_{self.tag}" if self.tag else "")
        png = picture(out / f"{stem}.png", f"{scn.name}: {request.job.name}, {kind}; contour error max "
                      f"{figures['contour_um']['max_um']:.1f} µm, RMS {figures['contour_um']['rms_um']:.1f} µm",
                      ref.um, looped.trace.table_um, contour, looped.trace.duty, ref.tick_s, scn.servo.duty_max)
        learning = {} if looped.learning is None else {"learning": looped.learning}
        return write({**head, "controller": kind, **figures, **learning, "chip": looped.chip, "png": png}, out, stem)
