"""Section: latency and memory on the chips, the estimate beside each measurement, and cost vs
accuracy against the float IK and the lut family's best."""

from __future__ import annotations

from nnik.report.document import (D_CYC, D_DIFF, D_UNIT, D_US, Fig, Section, Table, finite, keypath, lookup,
                                  not_run_cell, num, txt)
from nnik.report.measured import (clocks_per_cycle, cycles_to_us, implementations, lut_picked, lut_verdicts, pct_diff,
                                  target_names, target_status, worst)

PNG_COST = "cost_accuracy.png"
PNGS = (PNG_COST,)


def build(ctx) -> Section:
    m, unit = ctx.m, ctx.unit
    sec = Section("targets", "Latency and memory on the chips")
    if not isinstance(m.get("targets"), dict):
        sec.not_run.append("targets not run: no `targets` section in metrics.json")
    lat = Table("latency-table", "Latency per IK call (measured in the simulator)",
                ["target", "clock (MHz)", "cycles (mean)", "cycles (max)", "µs (mean)", "µs (max)",
                 "estimate (cycles)", "estimate vs measured (%)"])
    mem = Table("memory-table", "Memory", ["target", "flash (bytes)", "estimate (bytes)", "difference (%)",
                                          "RAM (bytes)", "estimate (bytes)", "difference (%)"])
    ran = []
    for tname in target_names(m):
        tm, reason = target_status(m, tname)
        if tm is None:
            lat.rows.append([txt(tname, "label"), not_run_cell(reason, 7)])
            mem.rows.append([txt(tname, "label"), not_run_cell(reason, 6)])
            continue
        ran.append((tname, tm))
        k = lambda *p: keypath("targets", tname, *p)  # noqa: E731
        est = tm.get("estimate") if isinstance(tm.get("estimate"), dict) else {}
        clock = tm.get("clock_hz")
        cpc = clocks_per_cycle(tname, tm)
        lat.rows.append([
            txt(tname, "label", title=f"{tm.get('compiler', '')} {tm.get('flags', '')}".strip()),
            num(None if not finite(clock) else clock / 1e6, 3, cls="num derived",
                title=f"{cpc} clock(s) per counted cycle"),
            num(tm.get("cycles"), D_CYC, k("cycles")), num(tm.get("cycles_max"), D_CYC, k("cycles_max")),
            num(cycles_to_us(tm.get("cycles"), tname, tm), D_US, cls="num derived"),
            num(cycles_to_us(tm.get("cycles_max"), tname, tm), D_US, cls="num derived"),
            num(est.get("cycles"), D_CYC, k("estimate", "cycles")) if est else txt("no estimate", "missing"),
            num(pct_diff(est.get("cycles"), tm.get("cycles")), D_DIFF, cls="num derived"),
        ])
        mem.rows.append([
            txt(tname, "label"),
            num(tm.get("flash_bytes"), D_CYC, k("flash_bytes")),
            num(est.get("flash_bytes"), D_CYC, k("estimate", "flash_bytes")) if est else txt("no estimate", "missing"),
            num(pct_diff(est.get("flash_bytes"), tm.get("flash_bytes")), D_DIFF, cls="num derived"),
            num(tm.get("ram_bytes"), D_CYC, k("ram_bytes")),
            num(est.get("ram_bytes"), D_CYC, k("estimate", "ram_bytes")) if est else txt("no estimate", "missing"),
            num(pct_diff(est.get("ram_bytes"), tm.get("ram_bytes")), D_DIFF, cls="num derived"),
        ])
    lat.note = ("µs = cycles × clocks per cycle / clock (PIC18 counts instruction cycles of 4 clocks; AVR counts "
                "clocks). Estimate: nnik's cost model, before compiling; difference = (estimate − measured) / measured.")
    sec.tables += [lat, mem]
    tc = Table("toolchain-table", "Toolchains", ["target", "compiler", "flags", "clock (Hz)"])
    for tname, tm in ran:
        tc.rows.append([txt(tname, "label"), txt(tm.get("compiler")), txt(tm.get("flags"), "mono"),
                        num(tm.get("clock_hz"), 0, keypath("targets", tname, "clock_hz"))])
    if ran:
        sec.tables.append(tc)

    # cost vs accuracy
    hdr = ["target", "implementation", "cycles (mean)", "µs", "flash (bytes)", "RAM (bytes)"] + \
          [f"{o} max ({unit})" for o in ctx.outputs]
    ca = Table("cost-table", "Cost vs accuracy: the MLP against the float math.h IK and the lut family's best", hdr)
    points: dict[str, list[dict]] = {}
    for tname, tm in ran:
        points[tname] = []
        for i in implementations(m, tname, tm):
            kp = i["keypath"]
            row = [txt(tname, "label"), txt(i["label"], f"impl-{i['kind']}"),
                   num(i["cycles"], D_CYC, keypath(*kp, "cycles")),
                   num(cycles_to_us(i["cycles"], tname, tm), D_US, cls="num derived"),
                   num(i["flash"], D_CYC, keypath(*kp, "flash_bytes")),
                   num(i["ram"], D_CYC, keypath(*kp, "ram_bytes"))]
            for j in range(ctx.n_out):
                v = lookup(i["err"], j)
                row.append(num(v, D_UNIT, f"{i['err_key']}/{j}" if i["err_key"] and v is not None else None))
            ca.rows.append(row)
            if finite(i["cycles"]) and worst(i["err"]) is not None and i["cycles"] > 0 and worst(i["err"]) > 0:
                points[tname].append(dict(label=i["label"], kind=i["kind"], cycles=float(i["cycles"]),
                                          err=worst(i["err"])))
    for tname in target_names(m):
        tm, reason = target_status(m, tname)
        if tm is None:
            ca.rows.append([txt(tname, "label"), not_run_cell(reason, 5 + ctx.n_out)])
    ca.note = ("MLP and lut error: the fixed-point model's delivered commands (bit-exact on the chip; the lut "
               "family's on its check set); float IK: as measured by its own harness. Lower-left is better in the picture.")
    sec.tables.append(ca)
    wins, losses = lut_verdicts(m)
    for w in wins:
        # a table beating the MLP is bad news, unless the table is the pick
        sec.verdicts.append(("good" if lut_picked(m) else "bad", w))
    for s in losses:
        sec.verdicts.append(("good", s))
    if ran and not wins and not losses:
        sec.not_run.append("table comparison not run: no lut family best verified on a target with cycles and errors")
    if any(points.values()):
        ctx.plot(sec, lambda: plot_cost(ctx, points))
    else:
        sec.not_run.append("cost vs accuracy picture not run: no target reports cycles together with errors")
    return sec

def plot_cost(ctx, points) -> Fig:
    from nnik.report import plots as rp

    rp.cost_accuracy(ctx.out / PNG_COST, points=points, unit=ctx.unit,
                     title=f"{ctx.m['name']}: cycles per IK vs max error")
    return Fig(PNG_COST, "cost vs accuracy per target",
               "Cycles per IK call against the worse output's max error, per target (log-log).")
