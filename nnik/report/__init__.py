"""The accuracy/latency report: what a user looks at before flashing.

:func:`write_report` reads whatever the pipeline has left in MODEL_DIR (``metrics.json`` is
required; ``model.pt``, ``data.npz`` and ``fixed_eval.npz`` are used when present) and writes
``index.html`` (self-contained: inline CSS, no scripts, PNGs beside it), ``report.md`` and the
PNGs into OUT_DIR (default ``MODEL_DIR/report``).

Nothing is left out silently: a section whose inputs are missing is shown as "not run" with the
reason. Every number taken from metrics.json sits in a ``<td>`` carrying the raw value in
``data-value`` and its place in metrics.json in ``data-key`` (``/``-separated, e.g.
``float/max_abs/0``); numbers computed here (physical units, µs, differences) carry
``data-value`` only.

The package: one module per section, each with ``build(ctx) -> Section`` (and ``PNGS``, the
pictures it writes), assembled in order by build.SECTIONS.  ``ctx`` is a context.Context: the
inputs (inputs.load_inputs), metrics.json as ``ctx.m``, the output folder, units, and
``ctx.plot(sec, fn)`` which runs a picture and turns a failure into a "not run" line.  Shared
pieces: document (Cell, Table, Fig, Section, num/txt/fmt), measured (targets and their
implementations in metrics.json), units, render (HTML, Markdown), plots (the PNGs).

To add a section (say "implementations": every family's best point and the pick):
write nnik/report/implementations.py with

    from nnik.report.document import Section, Table, num, txt

    def build(ctx) -> Section:
        sec = Section("implementations", "Implementations")
        ...                      # read ctx.m["implementations"]; say "not run" when it is absent
        return sec

and add ``implementations`` to the import and to SECTIONS in nnik/report/build.py, where it
should appear.  Cells built with ``num(value, digits, key)`` carry the metrics.json place the
report test checks every number against.
"""

from nnik.report.build import ALL_PNGS, REPORT_DIRNAME, SECTIONS, build_sections, write_report
from nnik.report.inputs import load_metrics
from nnik.report.summary import SUMMARY_HEADER, summary_rows

__all__ = ["ALL_PNGS", "REPORT_DIRNAME", "SECTIONS", "SUMMARY_HEADER", "build_sections", "load_metrics",
           "summary_rows", "write_report"]
