"""Assemble the report: every section module in order, then HTML, Markdown and the PNGs."""

from __future__ import annotations

from pathlib import Path

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
    for png in ALL_PNGS:  # no stale pictures from an earlier report
        (out_dir / png).unlink(missing_ok=True)
    sections = build_sections(inp, out_dir)
    index = out_dir / "index.html"
    index.write_text(render_html(sections, inp.metrics), encoding="utf-8")
    (out_dir / "report.md").write_text(render_markdown(sections, inp.metrics), encoding="utf-8")
    return index
