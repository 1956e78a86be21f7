"""A G-code job as one-way stages (`nnik job`).

    parse -> plan -> shape -> sample and IK -> chip co-simulation -> measure -> report
    parse.py  plan.py  shape.py   sample.py        cosim.py           measure.py  report.py

Each stage is one module with typed input and output (JobRequest -> ParsedJob -> PlannedJob ->
ShapedJob -> SampledJob [-> CoSimulated] -> MeasuredJob -> the figures) and imports only the stages
before it. The model directory is read once, into nnik.firmware.model_dir.ModelDir, and handed
down; no stage opens it. A kind of job (kind.JobKind) composes the stages: open_loop.OpenLoopJob,
and closed_loop.ClosedLoopJob for a DC-servo XY table:

    parse -> reference -> servo_loop (Python; the chip) -> servo_measure -> servo_report
             reference.py  servo_loop.py                   servo_measure.py  servo_report.py
"""
