"""Section: published tables (seed 000 Table 1, seed 004 Table 1) beside this run."""

from __future__ import annotations

import json
from pathlib import Path

from nnik.report.document import D_MS, D_PCT, Section, Table, finite, keypath, lookup, not_run_cell, num, txt
from nnik.report.inputs import METRICS_FILE
from nnik.report.measured import cycles_to_us, implementations, target_names, target_status

# ---- published references (labelled as such wherever shown) ----
PUB_000_SETUP = "PIC18F452, CCS compiler, 16 MHz clock (4 MIPS)"
PUB_000_MIPS = 4.0e6
PUB_000 = (  # (method, ROM words, time ms)
    ("IK with math.h", 1977, 258.6),
    ("MLP with math.h tanh", 2696, 38.0),
    ("MLP with polynomial tanh", 3590, 7.2),
)
PUB_004 = (  # (row, q1, q2, x, y) relative error, %
    ("without normalisation", 5.1851, 1.1009, 5.0147, 13.6855),
    ("with input normalisation to [0, 1]", 0.0508, 0.1017, 0.0807, 0.2008),
)


def build(ctx) -> Section:
    m = ctx.m
    sec = Section("references", "Published references beside this run")
    sec.paragraphs.append("Rows marked “published” are copied from the papers and were not measured here; "
                          "“this run” rows are this model's own measurements. Different chips, compilers and "
                          "networks: compare orders of magnitude, not digits.")
    t = Table("ref000-table", f"Seed 000 (CBA 2012), Table 1 — {PUB_000_SETUP}",
              ["source", "method", "ROM words", "flash (bytes)", "time (ms)", "cycles"])
    for method, words, ms in PUB_000:
        t.rows.append([txt("published (seed 000)", "published"), txt(method), num(words, 0, cls="num published"),
                       num(words * 2, 0, cls="num derived published", title="2 bytes per PIC18 program word"),
                       num(ms, 1, cls="num published"),
                       num(ms * 1e-3 * PUB_000_MIPS, 0, cls="num derived published",
                           title="instruction cycles at 4 MIPS")])
    for tname in target_names(m):
        tm, reason = target_status(m, tname)
        if tm is None:
            t.rows.append([txt(f"this run, {tname}", "label"), not_run_cell(reason, 5)])
            continue
        clock = tm.get("clock_hz")
        src = f"this run, {tname}" + (f" @ {clock / 1e6:g} MHz" if finite(clock) else "") + \
              (f", {tm['compiler']}" if tm.get("compiler") else "")
        for i in implementations(m, tname, tm):
            kp = i["keypath"]
            us = cycles_to_us(i["cycles"], tname, tm)
            t.rows.append([txt(src, "label"), txt(i["label"]),
                           num(None if not finite(i["flash"]) else i["flash"] / 2, 0, cls="num derived",
                               title="flash bytes / 2"),
                           num(i["flash"], 0, keypath(*kp, "flash_bytes")),
                           num(None if us is None else us / 1000, D_MS, cls="num derived"),
                           num(i["cycles"], 0, keypath(*kp, "cycles"))])
    t.note = ("Published flash bytes (2 per ROM word) and cycles (time × 4 MIPS) are derived from the published "
              "numbers; this run's ROM words are flash bytes / 2.")
    sec.tables.append(t)

    rel = lookup(m, "float", "rel_pct")
    t4 = Table("ref004-table", "Seed 004 (UNICAMP), Table 1 — relative error, % (mean |error| / output span)",
               ["source", "inputs", "q1 / output 1 (%)", "q2 / output 2 (%)", "x (%)", "y (%)"])
    for row, *vals in PUB_004:
        t4.rows.append([txt("published (seed 004)", "published"), txt(row)] +
                       [num(v, D_PCT, cls="num published") for v in vals])
    norm = lookup(m, "network", "normalize")
    label = f"this run, {m['name']} ({', '.join(ctx.outputs)})"
    inputs_txt = "normalised to [-1, 1]" if norm else "raw mm (--no-normalize)"
    if isinstance(rel, list):
        t4.rows.append([txt(label, "label"), txt(inputs_txt)] +
                       [num(lookup(rel, j), D_PCT, f"float/rel_pct/{j}") for j in range(2)] +
                       [txt("not measured", "missing"), txt("not measured", "missing")])
    else:
        t4.rows.append([txt(label, "label"), not_run_cell("no `float/rel_pct` in metrics.json", 5)])
    sib, sib_dir = _sibling_metrics(ctx)
    if sib is not None:
        srel = lookup(sib, "float", "rel_pct")
        snorm = lookup(sib, "network", "normalize")
        t4.rows.append([txt(f"this run's sibling {sib_dir.name}", "label"),
                        txt("normalised to [-1, 1]" if snorm else "raw mm (--no-normalize)")] +
                       [num(lookup(srel, j), D_PCT, cls="num derived") for j in range(2)] +
                       [txt("not measured", "missing"), txt("not measured", "missing")])
    else:
        other = "--no-normalize" if norm else "normalised"
        t4.rows.append([txt("the other normalisation", "label"),
                        not_run_cell(f"no {other} run of {m['name']} beside this one ({sib_dir})", 5)])
    if m["name"].startswith("hbot_unicamp"):
        cmp_note = "this run is that scenario, so the rows compare like with like (up to the fit)."
    else:
        cmp_note = f"this run is {m['name']}, so the rows show scale only, not a like-for-like comparison."
    t4.note = ("Seed 004 measured an HBOT with skewed axes (our hbot_unicamp); " + cmp_note +
               " x, y errors need the forward model of the commands and are not measured by nnik.")
    sec.tables.append(t4)
    return sec

def _sibling_metrics(ctx) -> tuple[dict | None, Path]:
    d = ctx.inp.model_dir.resolve()
    name = d.name
    other = d.parent / (name[: -len("-no-normalize")] if name.endswith("-no-normalize") else f"{name}-no-normalize")
    p = other / METRICS_FILE
    if p.is_file():
        try:
            sib = json.loads(p.read_text())
            if sib.get("name") == ctx.m.get("name"):
                return sib, other
        except (json.JSONDecodeError, UnicodeDecodeError, AttributeError):
            pass
    return None, other
