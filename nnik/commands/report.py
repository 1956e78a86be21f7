"""`nnik report MODEL_DIR`: the HTML and Markdown report of a model directory; `nnik run` and
`nnik search` end with its summary table too."""

from __future__ import annotations

from pathlib import Path

from rich.markup import escape
from rich.table import Table

from nnik.commands import common_options as co
from nnik.commands.model_dirs import add_model_dir
from nnik.files.outdir import check_model_dir, check_outdir
from nnik.report.console import console

HELP = "write the HTML and Markdown report of a model directory (the families, the pick, the chips, the jobs)"
DESCRIPTION = ("Write index.html, report.md and their pictures for MODEL_DIR from its metrics.json: every family's "
               "best and the pick, each measured on the host and the simulated chips (cycles, flash, bit-exactness), "
               "the MLP's accuracy, and the G-code jobs run on it; then print the summary table.")


def register(sub) -> None:
    p = co.add_command(sub, "report", HELP, DESCRIPTION)
    add_model_dir(p)
    co.add_outdir(p, "where the report is written", "MODEL_DIR/report/")
    p.set_defaults(func=cmd_report)


def print_report(model_dir: Path, out_dir: Path | None = None) -> None:
    from nnik.report import SUMMARY_HEADER, load_metrics, summary_rows, write_report

    index = write_report(model_dir, out_dir)
    t = Table(title=f"report: {index}")
    for h in SUMMARY_HEADER:
        t.add_column(h)
    for r in summary_rows(load_metrics(model_dir)):
        t.add_row(*map(escape, r))  # text, not markup: "[target]" in a detail is printed as it is
    console.print(t)


def cmd_report(args) -> None:
    print_report(check_model_dir(args.model_dir), check_outdir(Path(args.outdir)) if args.outdir else None)
