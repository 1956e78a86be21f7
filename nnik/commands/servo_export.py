"""`nnik export OUTDIR --arduino DIR` on a DC-servo xy_table: the tuned controller's Arduino library
for the Uno (nnik.firmware.servo.export): the servo runtime (encoder interrupts, PWM, the tick),
the controller's C with its gains, and a job stored in flash (its reference per tick), with an
arduino-mk Makefile. The job is --job's (default: the seed's circle, datasets/jobs/servo_circle.gcode), through the same
interpreter and planner as `nnik job`; the controller is --controller's (default: the chosen one)."""

from __future__ import annotations

from pathlib import Path

from nnik.errors import NnikError

DEFAULT_JOB = "servo_circle.gcode"  # the seed's 125 s circle: 25,000 ticks in the Uno's flash


def cmd_servo_export(args) -> None:
    from nnik.commands.servo_run import JOBS
    from nnik.firmware.gcode.job_input import JobOptions
    from nnik.firmware.servo.export import export_servo_library
    from nnik.job.parse import JobRequest
    from nnik.job.reference import job_reference
    from nnik.job.servo_dir import ServoDir

    if args.arduino is None:
        raise NnikError("a dc_servo xy_table's export is its Arduino library: give --arduino DIR", None, "--arduino")
    model = ServoDir.load(Path(args.model_dir))
    controller = model.controller(args.controller)
    job = Path(args.job) if args.job else JOBS / DEFAULT_JOB
    _, ref = job_reference(JobRequest(job, model.scenario, None, None, False, JobOptions()))
    lib = export_servo_library(Path(args.arduino), model.scenario.servo, controller, ref.counts,
                               start=tuple(int(c) for c in ref.counts[0]), name=model.scenario.name,
                               source=f"nnik export {Path(args.model_dir).name} ({job.name})")
    print(f"wrote Arduino library {lib['libname']} to {lib['dir']}/ (example {lib['example']}: {controller.kind}, "
          f"job {job.name} stored in {lib['job_bytes']:,} bytes of flash, {lib['ticks']:,} ticks)")
