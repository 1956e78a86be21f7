"""Section: the Pareto front of `nnik search`, the report's first figure (only when the selection
in metrics.json came from a search; otherwise the section is left out).

Pre-rounding max error (log) against cycles and against flash, one column of panels per chip:
every point of the search's front (filled: measured on the simulator; hollow: its estimate),
each family's best beside it when it is not on the front, the pick circled, the MLP's best
labelled (at its estimate, and so labelled, when it was not verified), the float math.h IK's
measured cycles as a reference line. Under it: a sentence naming the pick and how much it beats
the best point of another family, and the front's table.

A front point's measurements are shown only while the C they ran (OUTDIR/<row c_dir>/, where
`nnik search` verified it: c/alt/<family>/ for a family's best, targets/front/... otherwise)
still hashes as it did; otherwise the row says the C changed since, and the picture draws the
point at its estimate.
"""

from __future__ import annotations

from nnik.files.c_hash import dir_hash
from nnik.report.document import D_CYC, D_UNIT, Cell, Fig, Section, Table, keypath, not_run_cell, num, txt
from nnik.report.implementations import (CHIPS, _c_hash, _check_cell, best_point, comparable, estimated_costs, judged_max,
                                         float_ik_cycles, not_verified_sentence, searched, versus_other_family)

PNG = "search_front.png"
PNGS = (PNG,)


def current(ctx, r: dict) -> bool | None:
    """True: the row was measured and its C is unchanged; False: measured, but the C changed
    since; None: never measured (an estimate)."""
    if not r.get("measured") or not r.get("c_dir"):
        return None
    return dir_hash(ctx.inp.model_dir / r["c_dir"], ctx.m.get("name", "")) == r.get("c_hash")


def _measured_point(ctx, r: dict) -> dict:
    return {"family": r["family"], "err": r["pre_max"], "picked": r.get("picked"),
            "measured": {c: (v["cycles"], v["flash_bytes"]) for c, v in r["measured"].items()}
            if current(ctx, r) else {}, "estimated": estimated_costs(r)}


def points(ctx, srch: dict, sel: dict) -> list[dict]:
    """The front, then each family's best that is not on it; the MLP's best labelled."""
    pts = [_measured_point(ctx, r) for r in srch["front"]]
    keys = [(r["family"], r.get("model_hash")) for r in srch["front"]]
    for r in sel.get("implementations", []):
        k = (r["family"], r.get("model_hash"))
        p = pts[keys.index(k)] if k in keys else best_point(r)
        if k not in keys:
            pts.append(p)
        if r["family"] == "mlp":
            p["label"] = "MLP best" if p["measured"] else "MLP best (estimate)"
    return pts


def pick_sentence(ctx, srch: dict, sel: dict) -> str:
    tg, unit = sel["target"], ctx.unit
    chip = tg["chip"]
    pick = next((r for r in sel.get("implementations", []) if r.get("picked")), None)
    if not_verified_sentence(pick):
        return not_verified_sentence(pick)
    if pick is None or pick.get("cycles", {}).get(chip) is None:
        return f"The search found no point that meets max_error {tg['max_error']:g} {unit} within the limits on {chip}."
    if _c_hash(ctx, pick["family"]) != pick.get("c_hash"):
        return f"The pick's C in c/alt/{pick['family']}/ changed since it was measured (run `nnik search` again)."
    cyc, fl = pick["cycles"][chip], pick["flash_bytes"][chip]
    s = (f"`nnik search` picks {pick['describe']}: {pick['pre_max']:.4f} {unit} before rounding, {cyc:.0f} cycles and "
         f"{fl} B of flash on {chip}, measured on the simulator.")
    rows = [{"family": r["family"], "describe": r.get("describe"), "pre_max": judged_max(r),
             "cycles": r["measured"][chip]["cycles"], "flash": r["measured"][chip]["flash_bytes"]}
            for r in srch["front"] if current(ctx, r) and chip in r["measured"]]
    rows += [comparable(r, chip) for r in sel["implementations"]
             if (r.get("cycles") or {}).get(chip) and _c_hash(ctx, r["family"]) == r.get("c_hash")]
    return s + versus_other_family(rows, pick, tg, unit)


def front_sentence(srch: dict, sel: dict, unit: str) -> str:
    v = srch.get("front_verified") or {}
    fams = ", ".join(srch.get("front_families") or []) or "no family"
    s = (f"The front of {sum((srch.get('trials') or {}).get(k, 0) for k in ('complete', 'pruned', 'fail'))} trials "
         f"(study {srch.get('study')}) has {len(srch['front'])} points over {fams}; "
         f"{v.get('meeting_max_error', '?')} meet max_error {sel['target']['max_error']:g} {unit}, and ")
    if "cap" not in v:
        return s + "none was verified on the simulators (this study predates front verification)."
    return s + (f"{v.get('verified', 0)} of them (at most {v['cap']}, cheapest on {sel['target']['chip']} first) "
                "ran on the host and on both simulated chips; the rest are drawn hollow at their estimated cost.")


def _cost_cells(ctx, r: dict, i: int) -> list[Cell]:
    """avr/pic18 cycles, avr/pic18 flash, bit-exact: measured, the C changed since, or estimates."""
    base = ("search", "front", i)
    state = current(ctx, r)
    if state is False:
        return [not_run_cell(f"the C in {r['c_dir']}/ changed since it was measured", 5)]
    cells = []
    for what in ("cycles", "flash_bytes"):
        for chip in CHIPS:
            if state and chip in r["measured"]:
                cells.append(num(r["measured"][chip][what], D_CYC, keypath(*base, "measured", chip, what)))
            elif chip in (r.get("estimate") or {}):
                est = r["estimate"][chip][what]
                cells.append(Cell(f"{est:.0f} est.", value=est, cls="num derived", title=r.get("not_verified", "")))
            else:
                cells.append(num(None, D_CYC))
    ck = r.get("checks") or {}
    cells.append(txt(" / ".join(_check_cell({"host": ck.get("host"), "targets": ck}, w) for w in ("host", *CHIPS))
                     if state else "not run (estimate)", title=r.get("not_verified", "")))
    return cells


def build(ctx) -> Section | None:
    if not searched(ctx.m):  # no search, or a ladder's selection since: nothing of the search to show
        return None
    srch, sel = ctx.m["search"], ctx.m["selection"]
    sec = Section("search-front", "The search's Pareto front", figures_first=True)
    unit = ctx.unit
    ctx.plot(sec, lambda: plot(ctx, srch, sel))
    sec.paragraphs.append(pick_sentence(ctx, srch, sel))
    sec.paragraphs.append(front_sentence(srch, sel, unit))
    t = Table("search-front-table", "The front (pre-rounding error on the check set; cycles: mean per call on the "
              "simulator, or the estimate, marked est.; flash: the model's own bytes)",
              ["family", "configuration", f"pre max ({unit})", "avr cycles", "pic18 cycles", "avr flash B",
               "pic18 flash B", "bit-exact host / avr / pic18", "meets target", "pick"])
    for i, r in enumerate(srch["front"]):
        row = [txt(r["family"], "label"), txt(r.get("describe")),
               num(r["pre_max"], D_UNIT, keypath("search", "front", i, "pre_max"))]
        row += _cost_cells(ctx, r, i)
        row.append(Cell("yes" if r.get("meets_target") else "no", value=bool(r.get("meets_target")),
                        key=keypath("search", "front", i, "meets_target")))
        row.append(txt("PICK" if r.get("picked") else ""))
        t.rows.append(row)
    sec.tables.append(t)
    return sec


def plot(ctx, srch: dict, sel: dict) -> Fig | str:
    from nnik.report.implementations_plot import families_front

    if not srch["front"]:
        return "the search's front is empty (no trial completed)"
    fl = float_ik_cycles(ctx)
    families_front(ctx.out / PNG, points=points(ctx, srch, sel), chips=CHIPS, max_error=sel["target"]["max_error"],
                   unit=ctx.unit, float_ik=fl, title=f"{ctx.m.get('name')}: the search's Pareto front "
                   "(filled: measured; hollow: estimated)")
    ref = ("the dashed line is the float math.h IK's measured cycles" if fl else
           "the float math.h IK was not measured in this run (`nnik verify OUTDIR --target avr` measures it)")
    return Fig(PNG, "the search's Pareto front: error against cycles and flash per chip",
               "Pre-rounding max error (log) against cycles (top) and flash (bottom) on each chip, for every point of "
               "the search's Pareto front and each family's best beside it. The pick is circled; the MLP's best is "
               f"labelled; the dotted line is max_error; {ref}.")
