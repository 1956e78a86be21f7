"""Section: what to flash. Every implementation family's best point for the scenario's
[target], measured on both simulated chips, the pick, and where the MLP wins or loses.

A row's measurements are shown only while the C they ran is still what OUTDIR/c/alt/<family>/
holds (its hash is recomputed from the file); otherwise the row says the C changed since.
"""

from __future__ import annotations

from nnik.files.c_hash import dir_hash
from nnik.report.document import D_CYC, D_UNIT, Fig, Section, Table, keypath, lookup, not_run_cell, num, txt

PNG_FRONT = "implementations_front.png"
PNGS = (PNG_FRONT,)
CHIPS = ("avr", "pic18")


def _c_hash(ctx, family: str) -> str | None:
    return dir_hash(ctx.inp.model_dir / "c" / "alt" / family, ctx.m.get("name", ""))


def _check_cell(r: dict, where: str) -> str:
    """host, or a chip's fast and portable paths together."""
    cs = [r.get("host")] if where == "host" else [lookup(r, "targets", where), lookup(r, "targets", f"{where}_portable")]
    cs = [c for c in cs if isinstance(c, dict)]
    if not cs:
        return "—"
    ran = [c for c in cs if "not_run" not in c]
    if not ran:
        return "not run"
    bad = sum(int(c.get("mismatches") or 0) for c in ran)
    if not all(c.get("bit_exact") for c in ran):
        return f"NO ({bad} mismatches)"
    if len(cs) == 1:
        return "yes"
    return "yes (fast + portable)" if len(ran) == len(cs) else "yes (fast; portable not run)"


def not_verified_sentence(pick: dict | None) -> str | None:
    """For a pick whose c/NAME.c is not the C that was verified (report.inputs.mark_pick): the
    sentence that replaces every figure about it."""
    if pick and pick.get("pick_not_verified"):
        return f"The pick ({pick['family']}) is NOT verified: {pick['pick_not_verified']}."
    return None


def pick_sentence(sel: dict, unit: str) -> str:
    rows = sel["implementations"]
    tg = sel["target"]
    chip = tg["chip"]
    pick = next((r for r in rows if r.get("picked")), None)
    if not_verified_sentence(pick):
        return not_verified_sentence(pick)
    if pick is None:
        return f"No family met max_error {tg['max_error']:g} {unit} within the limits on {chip}."
    claim = (f" (claimed {pick['claimed_max']:.4f} {unit} against the machine, its reference's error included)"
             if "claimed_max" in pick else "")
    s = (f"nnik picks {pick['describe']}: {pick['pre_max']:.4f} {unit} before rounding{claim}, {pick['cycles'][chip]:.0f} "
         f"cycles and {pick['flash_bytes'][chip]} B of flash on {chip}.")
    s += versus_other_family([comparable(r, chip) for r in rows if lookup(r, "cycles", chip) is not None], pick, tg,
                             unit)
    missing = [r for r in rows if judged_max(r) > tg["max_error"]]
    if missing:
        s += " Missing the target: " + "; ".join(f"{r['family']} (best {judged_max(r):.4f} {unit})" for r in missing) + "."
    return s


def judged_max(r: dict) -> float:
    """The error a row is judged by against max_error: its claimed max for a measured machine
    (the reference's error included), else its pre-rounding max."""
    return r.get("claimed_max", r["pre_max"])


def comparable(r: dict, chip: str) -> dict:
    """A measured selection row as {family, describe, pre_max, cycles, flash} on the chip
    (pre_max: the error it is judged by, judged_max)."""
    return {"family": r["family"], "describe": r.get("describe"), "pre_max": judged_max(r),
            "cycles": r["cycles"][chip], "flash": r["flash_bytes"][chip]}


def versus_other_family(rows: list[dict], pick: dict, tg: dict, unit: str) -> str:
    """How the pick (a selection row, measured) compares with the cheapest measured point of another
    family that meets [target] (max_error, and the cycle and flash limits on the chip if set),
    among rows {family, describe, pre_max, cycles, flash} measured in the same harness."""
    chip = tg["chip"]
    pool = [r for r in rows if r["family"] != pick["family"] and r["pre_max"] <= tg["max_error"]
            and r["cycles"] <= (tg.get("max_cycles") or float("inf"))
            and r["flash"] <= (tg.get("max_flash_bytes") or float("inf"))]
    if not pool:
        return f" No point of another family that meets the target was measured on {chip}: nothing to compare."
    other = min(pool, key=lambda r: (r["cycles"], r["flash"]))
    cyc, fl = pick["cycles"][chip], pick["flash_bytes"][chip]
    oc, of = other["cycles"], other["flash"]
    speed = (f"the pick is {oc / cyc:.2f}x faster on {chip}" if oc >= cyc else
             f"measured, that point is {cyc / oc:.2f}x faster than the pick on {chip} (the pick is the cheapest of "
             "each family's best by estimate)")
    size = f"and needs {of / fl:.2f}x less flash" if of >= fl else f"but needs {fl / of:.2f}x its flash"
    return (f" The best point of another family that meets the target, {other['describe']} ({other['pre_max']:.4f} "
            f"{unit}), takes {oc:.0f} cycles and {of} B in the same harness: {speed}, {size}.")


def mlp_sentence(sel: dict, unit: str) -> str | None:
    rows = sel["implementations"]
    chip = sel["target"]["chip"]
    mlp = next((r for r in rows if r["family"] == "mlp"), None)
    if mlp is None or lookup(mlp, "cycles", chip) is None:
        return None
    if mlp.get("picked"):
        return f"The MLP earns its place here: it is the cheapest family that meets the target on {chip}."
    better = [r for r in rows if r is not mlp and lookup(r, "cycles", chip) is not None
              and judged_max(r) <= judged_max(mlp) and r["cycles"][chip] <= mlp["cycles"][chip]]
    if better:
        b = min(better, key=lambda r: r["cycles"][chip])
        return (f"The MLP loses here: {b['describe']} is at least as accurate ({judged_max(b):.4f} vs "
                f"{judged_max(mlp):.4f} {unit}) and {mlp['cycles'][chip] / b['cycles'][chip]:.2f}x faster on {chip}.")
    return (f"The MLP ({judged_max(mlp):.4f} {unit}, {mlp['cycles'][chip]:.0f} cycles on {chip}) is not dominated: no "
            "other family is both at least as accurate and at least as fast.")


def build(ctx) -> Section:
    sec = Section("implementations", "What to flash: every implementation family")
    sel = ctx.m.get("selection")
    if not isinstance(sel, dict) or not sel.get("implementations"):
        sec.not_run.append("no family selection in metrics.json (run `nnik run`)")
        return sec
    unit = ctx.unit
    tg = sel["target"]
    sec.paragraphs.append(pick_sentence(sel, unit))
    ms = mlp_sentence(sel, unit)
    if ms:
        sec.paragraphs.append(ms)
    sec.paragraphs.append(
        f"Target: max_error {tg['max_error']:g} {unit} before rounding on {sel['check_points']} {sel['check_set']} "
        f"points; the cheapest by measured cycles on {tg['chip']} wins, flash breaks ties. Inputs in units of "
        f"{sel['input_unit_um']:g} µm. Each family's best is in c/alt/<family>/, the pick in c/.")
    srch = ctx.m.get("search")
    if searched(ctx.m):
        done = sum((srch.get("trials") or {}).get(k, 0) for k in ("complete", "pruned", "fail"))
        sec.paragraphs.append(
            f"Found by `nnik search`: {done} trials of study {srch.get('study')} ({srch.get('storage')} storage); its "
            f"Pareto front of error, estimated cycles and flash has {len(srch.get('front') or [])} points over "
            f"{', '.join(srch.get('front_families') or []) or 'no family'}; the pick comes from the front of the "
            f"{srch.get('feasible_front', 0)} points that meet the target, each family's cheapest verified on the "
            "simulators. The report's first figure, above, draws that front with these points.")
    t = Table("implementations-table", "Each family's best point (pre-rounding error; cycles: mean per call on the "
              "simulator; flash: the model's own bytes)",
              ["family", "configuration", f"pre max ({unit})", f"RMS ({unit})", "avr cycles", "pic18 cycles",
               "avr flash B", "pic18 flash B", "bit-exact host / avr / pic18", "pick"])
    for i, r in enumerate(sel["implementations"]):
        base = ("selection", "implementations", i)
        row = [txt(r["family"], "label"), txt(r.get("describe"))]
        row.append(num(r.get("pre_max"), D_UNIT, keypath(*base, "pre_max")))
        row.append(num(max(r.get("rms") or [float("nan")]), D_UNIT))
        current = _c_hash(ctx, r["family"])
        if r.get("pick_not_verified"):
            row.append(not_run_cell(f"c/{ctx.m.get('name')}.c NOT verified: {r['pick_not_verified']}", 5))
        elif current is None or current != r.get("c_hash"):
            row.append(not_run_cell("the C in c/alt/" + r["family"] + "/ changed since it was measured", 5))
        else:
            for chip in CHIPS:
                row.append(num(lookup(r, "cycles", chip), D_CYC, keypath(*base, "cycles", chip)))
            for chip in CHIPS:
                row.append(num(lookup(r, "flash_bytes", chip), D_CYC, keypath(*base, "flash_bytes", chip)))
            row.append(txt(" / ".join(_check_cell(r, w) for w in ("host", *CHIPS))))
        row.append(txt(("PICK (NOT verified)" if r.get("pick_not_verified") else "PICK") if r.get("picked") else ""))
        t.rows.append(row)
    sec.tables.append(t)
    if not searched(ctx.m):  # with a search, the front's figure above shows these points
        ctx.plot(sec, lambda: plot_front(ctx, sel))
    return sec


def searched(m: dict) -> bool:
    """The selection came from `nnik search` and metrics.json holds its front (the report then
    leads with the front's figure)."""
    return lookup(m, "selection", "source") == "search" and isinstance(lookup(m, "search", "front"), list)


def _hollow(sel: dict) -> str:
    """What the hollow points are: the ladder's configurations, or `nnik search`'s Pareto front."""
    return "search's Pareto front" if sel.get("source") == "search" else "ladder"


def estimated_costs(r: dict) -> dict:
    """chip -> (estimated cycles, estimated flash) of a row carrying "estimate"."""
    return {c: (r["estimate"][c]["cycles"], r["estimate"][c]["flash_bytes"]) for c in CHIPS
            if c in (r.get("estimate") or {})}


def best_point(r: dict) -> dict:
    """A family's best (a selection row) as a point of the families picture."""
    return {"family": r["family"], "err": r["pre_max"], "picked": r.get("picked"), "best": True,
            "measured": {c: (r["cycles"][c], r["flash_bytes"][c]) for c in CHIPS if lookup(r, "cycles", c) is not None},
            # a best that was not verified (it misses the target) is drawn at its estimate
            "estimated": estimated_costs(r)}


def float_ik_cycles(ctx) -> dict:
    """chip -> measured cycles of the float math.h IK (targets.<chip>.baselines.float), where measured."""
    cyc = {c: lookup(ctx.m, "targets", c, "baselines", "float", "cycles") for c in CHIPS}
    return {c: v for c, v in cyc.items() if v}


def plot_front(ctx, sel: dict) -> Fig:
    from nnik.report.implementations_plot import families_front

    pts = [best_point(r) for r in sel["implementations"]]
    best_hash = {r["family"]: r.get("model_hash") for r in sel["implementations"]}
    for r in sel.get("ladder", []):
        if "pre_max" not in r or r.get("model_hash") == best_hash.get(r["family"]):
            continue
        pts.append({"family": r["family"], "err": r["pre_max"], "estimated": estimated_costs(r)})
    families_front(ctx.out / PNG_FRONT, points=pts, chips=CHIPS, max_error=sel["target"]["max_error"], unit=ctx.unit,
                   float_ik=float_ik_cycles(ctx), title=f"{ctx.m.get('name')}: error against cost, "
                   f"every family (filled: measured best; hollow: {_hollow(sel)}, estimated)")
    return Fig(PNG_FRONT, "error against cycles and flash per family",
               "Pre-rounding max error (log) against cycles (top) and flash (bottom) on each chip. The pick is "
               "circled; the MLP's best is labelled; the dotted line is max_error.")
