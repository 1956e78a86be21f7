"""Stage 7 of a job, report: the picture (OUTDIR/job/JOB.png: the path, the reached points
coloured by their contour error) and the figures (OUTDIR/job/JOB.json), written whole.

MeasuredJob (+ the chip's figures, or why it did not run) -> the job's figures as written.
"""

from __future__ import annotations

import json
from pathlib import Path

from nnik.files.atomic_write import write_file_atomic
from nnik.firmware.gcode.plot import job_png
from nnik.job.measure import MeasuredJob


def picture(measured: MeasuredJob, out: Path) -> str:
    """OUTDIR/job/JOB.png; its path."""
    shaped = measured.sampled.shaped
    cfg, res, job = shaped.cfg, measured.figures, shaped.parsed.request.job
    title = (f"{res['scenario']}: {job.name}, {res['motion']['job_s']:.2f} s ({cfg.sample_hz} Hz samples, shaper "
             f"{cfg.shaper}); contour error max "
             f"{res['contour_um']['max']:.1f} µm, RMS {res['contour_um']['rms']:.1f} µm")
    return str(job_png(out / f"{job.stem}.png", title, shaped.plan, cfg, measured.plot, measured.sampled.segments))


def report(measured: MeasuredJob, chip: dict, png: str, out: Path) -> dict:
    """The figures with the chip's and the picture's path, written to OUTDIR/job/JOB.json."""
    res = {**measured.figures, "chip": chip, "png": png}
    write_file_atomic(out / f"{measured.sampled.shaped.parsed.request.job.stem}.json", json.dumps(res, indent=2) + "\n")
    return res
