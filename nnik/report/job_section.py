"""The report's G-code job section: what `nnik job` left in OUTDIR/job/, ready to embed.

Hook: the report calls job_section_png(outdir) and, when the list is not empty, shows each
"png" with its "caption" (and may tabulate "row" under JOB_HEADER from nnik.report.job_summary).
"""

from __future__ import annotations

import json
from pathlib import Path

from nnik.files.outdir import JOB_DIR
from nnik.report.job_summary import JOB_HEADER, job_row


def job_section_png(outdir: Path) -> list[dict]:
    """[{"png": Path, "caption": str, "row": tuple}] for every job run in OUTDIR/job/ (sorted)."""
    items = []
    for js in sorted((Path(outdir) / JOB_DIR).glob("*.json")):
        try:
            res = json.loads(js.read_text())
        except (OSError, ValueError):
            continue
        png = js.with_suffix(".png")
        if not png.is_file() or "contour_um" not in res:
            continue
        row = job_row(res)
        cap = dict(zip(JOB_HEADER, row))
        items.append({"png": png, "row": row, "res": res, "caption": (
            f"G-code job {res['job']}: {res['segments']} segments, {res['steps']} steps; contour error max / RMS "
            f"{cap['contour max / RMS (µm)']} µm (IK {cap['IK max (µm)']}, chord {cap['chord max (µm)']} µm); "
            f"simulated Uno: {cap['chip steps']} steps, sample loop {cap['sample loop CPU']} of the CPU; job time "
            f"{cap['job time (s)']} s ({cap['planner / shaper']})")})
    return items


__all__ = ["JOB_HEADER", "job_section_png"]
