"""Assemble the report: every section module in order, then HTML, Markdown and the PNGs."""

from __future__ import annotations

import os
from pathlib import Path

from nnik.files.atomic_write import fsync_dir, held_interrupt, temporary_folder

from nnik.report import (accuracy, files, implementations, jobs, reference, references, scenario, search_front, summary,
                         tanh, targets, training, verification)
from nnik.report.context import Context
from nnik.report.document import Section
from nnik.report.inputs import Inputs, load_inputs
from nnik.report.render import render_html, render_markdown

REPORT_DIRNAME = "report"
# the sections, in the order the report shows them: each module has build(ctx) -> Section and
# may list the PNGs it writes in PNGS (search_front: only with a search; its picture is the first)
SECTIONS = (summary, search_front, implementations, reference, jobs, scenario, accuracy, verification, tanh, targets,
            training, references, files)
ALL_PNGS = tuple(png for mod in SECTIONS for png in getattr(mod, "PNGS", ()))


def build_sections(inp: Inputs, out_dir: Path) -> list[Section]:
    """Every section in order; a module whose build returns None has nothing to show for this run."""
    ctx = Context(inp, out_dir)
    return [sec for sec in (mod.build(ctx) for mod in SECTIONS) if sec is not None]


def write_report(model_dir: Path, out_dir: Path | None = None) -> Path:
    """Write OUT_DIR/index.html, report.md and the PNGs for MODEL_DIR; return the index.html path.

    Default OUT_DIR: MODEL_DIR/report. Raises NnikError if MODEL_DIR has no usable metrics.json.
    """
    model_dir = Path(model_dir)
    out_dir = Path(out_dir) if out_dir is not None else model_dir / REPORT_DIRNAME
    inp = load_inputs(model_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    # built whole in a folder beside, then moved in file by file (pictures first, index.html last):
    # a full disk or a kill while building leaves the earlier report as it was
    with temporary_folder(out_dir.parent, f".{out_dir.name}.staging-") as stage:
        sections = build_sections(inp, stage)
        (stage / "report.md").write_text(render_markdown(sections, inp.metrics), encoding="utf-8")
        (stage / "index.html").write_text(render_html(sections, inp.metrics), encoding="utf-8")
        made = sorted(stage.iterdir(), key=lambda p: p.name == "index.html")
        with held_interrupt():
            for old in out_dir.glob("*.png"):  # no stale pictures from an earlier report
                if (old.name in ALL_PNGS or old.name.startswith(jobs.PNG_PREFIX)) and not (stage / old.name).exists():
                    old.unlink()
            for p in made:
                os.replace(p, out_dir / p.name)
        fsync_dir(out_dir)
    return out_dir / "index.html"
