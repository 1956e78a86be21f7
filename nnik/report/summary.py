"""The summary: a compact table for the terminal (summary_rows) and the report's first section."""

from __future__ import annotations

from nnik.report.document import D_CYC, D_LSB, D_UM, D_UNIT, D_US, Section, Table, finite, fmt, lookup, txt
from nnik.report.measured import cycles_to_us, lut_picked, lut_verdicts, target_names, target_status

SUMMARY_HEADER = ("item", "result", "detail")
DEFAULT_CLOCK_HZ = 16_000_000  # the simulated chips run at 16 MHz (targets/avr.py, targets/pic18.py)


def _vec(v, digits=D_UNIT) -> str:
    if not isinstance(v, (list, tuple)):
        return "—"
    return " / ".join(fmt(x, digits) for x in v)


def _chip_row(label: str, t: str, tm: dict | None, reason: str) -> tuple[str, ...]:
    if tm is None:
        return (label, "not run", reason)
    us = cycles_to_us(tm.get("cycles"), t, {"clock_hz": DEFAULT_CLOCK_HZ, **tm})
    clock = tm.get("clock_hz", DEFAULT_CLOCK_HZ)
    mhz = f" @ {float(clock) / 1e6:g} MHz" if finite(clock) else ""
    exact = "bit-exact" if tm.get("bit_exact") else f"NOT bit-exact ({tm.get('mismatches', '?')} mismatches)"
    path = f", {tm['path']} path" if tm.get("path") else ""
    return (label, f"{fmt(tm.get('cycles'), D_CYC)} cycles = {fmt(us, D_US)} µs{mhz}",
            f"flash {fmt(tm.get('flash_bytes'), D_CYC)} B, RAM {fmt(tm.get('ram_bytes'), D_CYC)} B, {exact}{path}")


def _pick_rows(metrics: dict, unit: str) -> list[tuple[str, ...]]:
    """The pick first (what c/NAME.c holds), its figures per chip, then each family's best."""
    sel = metrics.get("selection")
    if not isinstance(sel, dict):
        return [("pick (c/NAME.c)", "not run", "no selection yet: run `nnik select OUTDIR`")]
    impls = sel.get("implementations", [])
    pick = next((r for r in impls if r.get("picked")), None)
    tg = sel.get("target", {})
    chip = tg.get("chip", "avr")
    rows: list[tuple[str, ...]] = []
    if pick:
        rows.append(("pick (c/NAME.c)", f"{pick['family']}: max {fmt(pick.get('pre_max'), D_UNIT)} {unit} pre-rounding",
                     f"{pick.get('describe')}; {fmt(lookup(pick, 'cycles', chip), D_CYC)} cycles, "
                     f"{fmt(lookup(pick, 'flash_bytes', chip), D_CYC)} B on {chip} (target {tg.get('max_error')} {unit})"))
        for t in target_names(metrics):
            tm = (pick.get("targets") or {}).get(t)
            ok = isinstance(tm, dict) and "not_run" not in tm
            rows.append(_chip_row(t, t, tm if ok else None,
                                  str(tm["not_run"]) if isinstance(tm, dict) and "not_run" in tm
                                  else f"the pick was not run on {t}"))
    else:
        rows.append(("pick (c/NAME.c)", "none", f"no family met max_error {tg.get('max_error')} {unit}"))
    for r in impls:
        if r.get("skipped") or "pre_max" not in r:
            continue
        meets = r.get("claimed_max", r["pre_max"]) <= tg.get("max_error", float("inf"))  # a measured machine: its claim
        cyc = " / ".join(f"{t} {fmt(lookup(r, 'cycles', t), D_CYC)}" for t in target_names(metrics))
        rows.append((f"family {r['family']}" + (" (pick)" if r.get("picked") else ""),
                     f"max {fmt(r['pre_max'], D_UNIT)} {unit}" + ("" if meets else " (misses)"),
                     f"{r.get('describe')}; cycles {cyc}"))
    return rows


def summary_rows(metrics: dict) -> list[tuple[str, ...]]:
    """A compact table for the terminal: (item, result, detail) per row, every part shown.

    The pick (c/NAME.c) leads, and the per-chip rows (avr, pic18) are the pick's; each family's
    best follows, then the MLP family's own figures, each labelled "mlp ...". Columns are
    SUMMARY_HEADER. Missing sections appear as ("...", "not run", reason).
    """
    unit = metrics.get("unit", "")
    rows: list[tuple[str, ...]] = _pick_rows(metrics, unit)
    net = metrics.get("network") or {}
    shape = "-".join(map(str, net.get("shape", []))) or "?"
    rows.append(("scenario", str(metrics.get("name", "?")),
                 f"{metrics.get('mechanism', '?')}; MLP family {shape} {net.get('mode', '')}, "
                 f"{net.get('parameters', '?')} parameters"))
    n_test = lookup(metrics, "dataset", "n_test")
    truth = lookup(metrics, "dataset", "truth", default="truth")
    aff = metrics.get("affine_only")
    if isinstance(aff, dict):
        rows.append(("affine baseline", f"max {_vec(aff.get('max_abs'))} {unit}", f"RMS {_vec(aff.get('rms'))}"))
    fl = metrics.get("float")
    if isinstance(fl, dict):
        pos = fl.get("position_um")
        extra = f"; position max {fmt(pos.get('max'), D_UM)} µm" if isinstance(pos, dict) else ""
        rows.append(("mlp float64", f"max {_vec(fl.get('max_abs'))} {unit}",
                     f"RMS {_vec(fl.get('rms'))}; vs {truth}, {n_test} points{extra}"))
    else:
        rows.append(("mlp float64", "not run", "no `float` section in metrics.json"))
    fx = metrics.get("fixed")
    if isinstance(fx, dict):
        rows.append(("mlp fixed point (host model)", f"max {_vec(fx.get('max_abs'))} {unit}",
                     f"delivered max {_vec(fx.get('delivered_max_abs'))}; "
                     f"tanh {fx.get('tanh_variant', '?')}; {fx.get('weights_bytes', '?')} weight bytes"))
    else:
        rows.append(("mlp fixed point (host model)", "not run", "no `fixed` section in metrics.json"))
    host = metrics.get("host")
    if isinstance(host, dict) and "not_run" in host:
        rows.append(("mlp C on host", "not run", str(host["not_run"])))
    elif isinstance(host, dict):
        ok = bool(host.get("bit_exact"))
        rows.append(("mlp C on host", "bit-exact" if ok else "NOT bit-exact",
                     f"{host.get('mismatches', '?')} mismatches over {host.get('points', '?')} points"))
    else:
        rows.append(("mlp C on host", "not run", "no `host` section in metrics.json"))
    th = metrics.get("tanh")
    if isinstance(th, dict):
        rows.append(("mlp integer tanh", str(th.get("variant", "?")),
                     f"max {fmt(th.get('max_lsb'), D_LSB)} LSB, RMS {fmt(th.get('rms_lsb'), D_LSB)} LSB of Q15"))
    else:
        rows.append(("mlp integer tanh", "not run", "no `tanh` section in metrics.json"))
    for t in target_names(metrics):
        tm, reason = target_status(metrics, t)
        rows.append(_chip_row(f"mlp on {t}", t, tm, reason))
    wins, _ = lut_verdicts(metrics)
    if wins:
        rows.append(("lut family best", "wins, the pick" if lut_picked(metrics) else "wins",
                     wins[0] + (f" (and {len(wins) - 1} more)" if len(wins) > 1 else "")))
    onnx = metrics.get("onnx")
    if isinstance(onnx, dict):
        rows.append(("mlp ONNX vs torch", "ok" if onnx.get("ok") else "FAILED",
                     f"max |diff| {fmt(onnx.get('max_abs_diff'), 'sci')} (tolerance {onnx.get('tolerance', '?')})"))
    return rows


def build(ctx) -> Section:
    sec = Section("summary", "Summary")
    t = Table("summary-table", "At a glance", list(SUMMARY_HEADER))
    for r in summary_rows(ctx.m):
        cls = "notrun" if r[1] == "not run" else ("bad" if r[1].startswith("NOT") or r[1] in ("FAILED", "wins") else "")
        t.rows.append([txt(r[0], "label"), txt(r[1], cls), txt(r[2])])
    sec.tables.append(t)
    return sec
