"""Section: the files and metrics.json sections the report was made from."""

from __future__ import annotations

from nnik.report.document import Cell, Section, Table, txt


def build(ctx) -> Section:
    sec = Section("inputs", "Inputs")
    t = Table("inputs-table", f"Files read from {ctx.inp.model_dir}", ["file", "present", "what"])
    for f, ok, note in ctx.inp.files:
        t.rows.append([txt(f, "mono"), Cell("yes" if ok else "no", cls="good" if ok else "notrun"), txt(note)])
    for k in ("fixed", "host", "tanh", "targets"):
        ok = k in ctx.m
        t.rows.append([txt(f"metrics.json `{k}`", "mono"), Cell("yes" if ok else "no", cls="good" if ok else "notrun"),
                       txt("present" if ok else f"not run: no `{k}` section in metrics.json")])
    sec.tables.append(t)
    return sec
