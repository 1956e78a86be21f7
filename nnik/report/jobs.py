"""Section: G-code jobs. What `nnik job` left in OUTDIR/job/: per job the contour error (split
into the IK's, the rounding to whole steps and the chords), whether the simulated Uno stepped
exactly as the Python model, its cost per segment and the segment rate, and the job's PNG
(copied beside the report as job_<job>.png)."""

from __future__ import annotations

import shutil

from pathlib import Path

from nnik.report import job_dynamics
from nnik.report.job_section import JOB_HEADER, job_section_png
from nnik.report.document import Fig, Section, Table, txt

PNG_PREFIX = "job_"
NUMERIC = {"segments", "steps", "contour max / RMS (µm)", "IK max (µm)", "rounding max (µm)", "chord max (µm)",
           "cycles/sample", "sample loop CPU", "flash / RAM (B)"}


def build(ctx) -> Section:
    sec = Section("jobs", "G-code jobs on the simulated Uno")
    items = job_section_png(ctx.inp.model_dir)
    if not items:
        sec.not_run.append("not run — run `nnik job OUTDIR JOB.gcode`")
        return sec
    sec.paragraphs.append(
        "Each job runs through the firmware's logic in Python (segments, the IK, Bresenham steps) and through the "
        "library's G-code sketch on a simulated Arduino Uno (simavr); \"equal\" means every step fell on the same "
        "tick of the same segment in the same direction. The contour error is the tool point the steps reach "
        "against the programmed path; IK, rounding and chord split it into the IK's own error, the rounding to "
        "whole steps and the straight segments. Cycles/segment: the sketch's busy time (parsing, segmenting, "
        "the IK) per segment.")
    t = Table("jobs-table", "G-code jobs (from job/<job>.json)", list(JOB_HEADER))
    for it in items:
        t.rows.append([txt(v, "num" if h in NUMERIC else "label" if h == "job" else "") for h, v in
                       zip(JOB_HEADER, it["row"])])
        if any("DIFFER" in str(v) for v in it["row"]):
            sec.verdicts.append(("bad", f"{it['png'].stem}: the chip's steps differ from the Python model's"))
    sec.tables.append(t)
    for it in items:
        name = f"{PNG_PREFIX}{it['png'].name}"
        ctx.plot(sec, lambda it=it, name=name: _copy(ctx, it, name))
    for it in items:  # the belts (issue 18): every compensation on the tip, and its picture
        res = it["res"]
        if not res.get("dynamics"):
            continue
        sec.tables.extend(job_dynamics.tables(res))
        png = Path(res["dynamics"]["png"])
        if png.is_file():
            dyn = {"png": png, "caption": (
                f"{res['job']}: the programmed path, the tip with no compensation and with {res['dynamics']['chosen']}, "
                "and the tip's contour error over time (the tip integrated from the firmware's steps through each "
                "axis's spring-damper)")}
            ctx.plot(sec, lambda it=dyn, name=f"{PNG_PREFIX}{png.name}": _copy(ctx, it, name))
    return sec


def _copy(ctx, it: dict, name: str) -> Fig:
    shutil.copyfile(it["png"], ctx.out / name)
    return Fig(name, f"G-code job {Path(it['png']).stem}", it["caption"])
