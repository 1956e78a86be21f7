"""Section: the fixed-point export and the bit-exactness of the generated C."""

from __future__ import annotations

from nnik.report.document import Cell, Section, Table, keypath, not_run_cell, num, txt
from nnik.report.measured import target_names, target_status


def build(ctx) -> Section:
    m = ctx.m
    sec = Section("fixed", "Fixed point and bit-exactness")
    fx = m.get("fixed")
    if isinstance(fx, dict):
        t = Table("fixed-table", "Fixed-point export", ["item", "value"])
        t.rows.append([txt("tanh variant", "key"), txt(fx.get("tanh_variant"))])
        t.rows.append([txt("weights (bytes)", "key"), num(fx.get("weights_bytes"), 0, "fixed/weights_bytes")])
        qf = fx.get("q_formats")
        if isinstance(qf, dict):
            for k, v in _flatten(qf):
                t.rows.append([txt(f"Q format: {k}", "key"), txt(v)])
        sec.tables.append(t)
    else:
        sec.not_run.append("fixed-point export not run: no `fixed` section in metrics.json")
    t = Table("verify-table", "Generated C vs the Python integer model",
              ["where", "bit-exact", "mismatches", "points", "compiler", "flags"])
    host = m.get("host")
    if isinstance(host, dict) and "not_run" in host:
        t.rows.append([txt("host", "label"), not_run_cell(host["not_run"], 5)])
    elif isinstance(host, dict):
        ok = bool(host.get("bit_exact"))
        t.rows.append([txt("host", "label"), Cell("yes" if ok else "NO", value=ok, key="host/bit_exact",
                                                  cls="good" if ok else "bad"),
                       num(host.get("mismatches"), 0, "host/mismatches"), num(host.get("points"), 0, "host/points"),
                       txt(host.get("compiler")), txt(host.get("flags"))])
    else:
        t.rows.append([txt("host", "label"), not_run_cell("no `host` section in metrics.json", 5)])
    for tname in target_names(m):
        tm, reason = target_status(m, tname)
        if tm is None:
            t.rows.append([txt(tname, "label"), not_run_cell(reason, 5)])
            continue
        ok = bool(tm.get("bit_exact"))
        t.rows.append([txt(tname, "label"), Cell("yes" if ok else "NO", value=ok, key=keypath("targets", tname, "bit_exact"),
                                                 cls="good" if ok else "bad"),
                       num(tm.get("mismatches"), 0, keypath("targets", tname, "mismatches")),
                       num(tm.get("points"), 0, keypath("targets", tname, "points")),
                       txt(tm.get("compiler")), txt(tm.get("flags"))])
    sec.tables.append(t)
    return sec


def _flatten(d: dict, prefix: str = "") -> list[tuple[str, str]]:
    out = []
    for k, v in d.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out += _flatten(v, f"{name}.")
        elif isinstance(v, (list, tuple)):
            out.append((name, ", ".join(map(str, v))))
        else:
            out.append((name, str(v)))
    return out
