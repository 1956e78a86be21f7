"""What `nnik` prints on the console: the accuracy, selection, reference and search-front tables
(rich), on the one console the CLI writes to."""

from __future__ import annotations

import sys

from rich.console import Console
from rich.table import Table


console = Console(highlight=False, width=None if sys.stdout.isatty() else 140)


def _fmt(values, digits=3) -> str:
    return " / ".join(f"{v:.{digits}f}" for v in values)


def print_accuracy(m: dict) -> None:
    unit = m["unit"]
    t = Table(title=f"{m['name']}: {'-'.join(map(str, m['network']['shape']))} {m['network']['mode']} MLP, "
                    f"error vs {m['dataset']['truth']} ({m['dataset']['n_test']} test points)")
    t.add_column("model")
    for o in m["outputs"]:
        t.add_column(f"{o} max ({unit})", justify="right")
    t.add_column(f"RMS ({unit})", justify="right")
    t.add_column(f"p99 ({unit})", justify="right")
    t.add_column("rel. % (004)", justify="right")
    rows = [("affine least squares", m["affine_only"]), ("MLP float64", m["float"])]
    if "fixed" in m:
        rows.append(("MLP fixed point, pre-rounding", m["fixed"]))
        rows.append(("MLP fixed point, delivered", {"max_abs": m["fixed"]["delivered_max_abs"],
                                                    "rms": m["fixed"]["delivered_rms"]}))
    b = m.get("baselines", {})
    if b.get("float", {}).get("max_abs"):
        rows.append(("baseline: float math.h C, delivered", b["float"]))
    lut = next((r for r in m.get("implementations") or [] if r.get("family") == "lut" and "pre_max_abs" in r), None)
    if lut:  # what a firmware engineer would write: a table (the lut family's best, on its check set)
        rows.append((f"lut family best: {lut['describe']}, pre-rounding", {"max_abs": lut["pre_max_abs"], "rms": lut["rms"]}))
    for label, s in rows:
        rel = _fmt(s["rel_pct"], 4) if "rel_pct" in s else "-"
        p99 = _fmt(s["p99"], 4) if "p99" in s else "-"
        t.add_row(label, *[f"{v:.4f}" for v in s["max_abs"]], _fmt(s["rms"], 4), p99, rel)
    console.print(t)
    pos = m["float"].get("position_um")
    if pos:
        console.print(f"position error of the float MLP's commands: max {pos['max']:.2f} um, RMS {pos['rms']:.2f} um")
    console.print(f"ONNX vs torch: max |diff| {m['onnx']['max_abs_diff']:.2e} (tolerance {m['onnx']['tolerance']:g}); "
                  f"training {_seconds(m.get('train_seconds'))}")
    if "fixed" in m:
        f = m["fixed"]
        console.print(f"fixed point: tanh '{f['tanh_variant']}', int{f['weight_bits']} weights, "
                      f"{f['weights_bytes']} bytes of tables, model hash {f['model_hash']}")
    if "host" in m:
        h = m["host"]
        console.print(f"host C (gcc, UBSan+ASan): {h['points']} points, {h['mismatches']} mismatches vs the integer model, "
                      f"overflows {sum(h['overflows'].values())}, saturations in domain "
                      f"{sum(v for k, v in h['saturations'].items() if k != 'outside')}")


def print_selection(m: dict) -> None:
    """The families table: each family's best point, measured on both chips; the pick marked."""
    sel = m.get("selection")
    if not sel:
        return
    tg = sel["target"]
    unit = m["unit"]
    t = Table(title=f"{m['name']}: every family's best for max_error {tg['max_error']:g} {unit} on {tg['chip']} "
                    f"(pre-rounding, {sel['check_points']} {sel['check_set']} points)")
    for col in ("family", "configuration", f"pre max ({unit})", "avr cycles", "pic18 cycles", "avr flash B",
                "pic18 flash B", "bit-exact host/avr/pic18 (fast+portable)", "pick"):
        t.add_column(col, justify="left" if col in ("family", "configuration", "pick") else "right")
    for r in sel["implementations"]:
        cyc, fl = r.get("cycles", {}), r.get("flash_bytes", {})
        tg_ = r.get("targets", {})
        checks = [[r.get("host") or {}], *[[tg_.get(k, {}), tg_.get(f"{k}_portable", {})] for k in ("avr", "pic18")]]
        def verdict(cs):
            if not any(cs):
                return "-"  # not verified: no family reached max_error
            ran = [c for c in cs if c and "not_run" not in c]
            if not ran:
                return "not run"
            if not all(c.get("bit_exact") for c in ran):
                return "NO"
            return "yes" if len(ran) == len(cs) else "yes (fast)"

        ok = "/".join(verdict(cs) for cs in checks)
        meets = r.get("claimed_max", r["pre_max"]) <= tg["max_error"]
        t.add_row(r["family"], r["describe"], f"{r['pre_max']:.4f}" + ("" if meets else " (misses)"),
                  *[f"{cyc[k]:.0f}" if cyc.get(k) is not None else "-" for k in ("avr", "pic18")],
                  *[f"{fl[k]}" if fl.get(k) is not None else "-" for k in ("avr", "pic18")],
                  ok, "PICK" if r["picked"] else "")
    pick = sel.get("pick")
    if pick:
        row = next((r for r in sel["implementations"] if r.get("picked")), {})
        chip = tg.get("chip", "avr")
        cyc = (row.get("cycles") or {}).get(chip)
        fl = (row.get("flash_bytes") or {}).get(chip)
        figures = f": {cyc:.0f} cycles, {fl} B flash on {chip}" if cyc is not None and fl is not None else ""
        console.print(f"[bold]pick:[/bold] {pick['describe']} -> c/{pick['file']}{figures}, max {row.get('pre_max', 0):.4f} "
                      f"{unit} pre-rounding (every family's best in c/alt/<family>/)")
        print_reference(m, row)
        if not sel.get("pick_meets_max_error", True):
            console.print(f"[bold yellow]note:[/bold yellow] no family met the default max_error {tg['max_error']:g} {unit} "
                          "(the scenario has no \\[target] max_error), so the most accurate verified family best is the "
                          "pick; set \\[target] max_error to make a miss an error")
    console.print(t)


def print_reference(m: dict, pick_row: dict) -> None:
    """A measured machine: what its figures are measured against, the pick's claim, the hull warning."""
    ref = m.get("reference")
    if not isinstance(ref, dict):
        return
    unit = m["unit"]
    cv = ", ".join(f"{k} {max(v['cv_rms']):.3f}" for k, v in ref["candidates"].items() if "cv_rms" in v)
    console.print(f"reference: {ref['chosen']} fitted to {ref['marks']} marks (CV RMS {cv}); noise {ref['noise']['source']}; "
                  f"est. error vs the machine max {ref['error_max']:.3g} {unit}, noise floor {ref['noise_floor']:.3g} {unit}")
    if "claimed_max" in pick_row:
        console.print(f"claimed max error of the pick: {pick_row['claimed_max']:.3g} {unit} inside the marks' hull "
                      f"(implementation {pick_row['pre_max']:.3g} vs the reference, with the reference's bootstrapped "
                      f"error, {ref['error_max']:.3g} alone)")
    if ref.get("workspace_warning"):
        console.print(f"[bold yellow]warning:[/bold yellow] {ref['workspace_warning']}")

def print_front(res: dict, unit: str) -> None:
    t = Table(title=f"study {res['study']} ({res['storage']}): Pareto front of error, estimated cycles and flash "
                    f"({sum(r['meets_target'] for r in res['front'])} of {len(res['front'])} points meet \\[target])")
    for col in ("trial", "family", "configuration", f"pre max ({unit})", "est. cycles", "est. flash B", "meets"):
        t.add_column(col, justify="left" if col in ("family", "configuration") else "right")
    for r in res["front"]:
        t.add_row(str(r["trial"]), r["family"], r["describe"] or "", f"{r['pre_max']:.4f}", f"{r['cycles']:.0f}",
                  str(r["flash_bytes"]), "yes" if r["meets_target"] else "")
    console.print(t)
    trials = res["trials"]
    console.print("trials: " + ", ".join(f"{v} {k}" for k, v in trials.items() if v))


def _seconds(v) -> str:
    """A recorded duration, or "time not recorded" (a model trained elsewhere, its time file gone)."""
    return f"{v:.1f} s" if isinstance(v, (int, float)) and v == v else "time not recorded"
