"""Section: accuracy per output against the truth, in output and physical units, with the error
map and histogram."""

from __future__ import annotations

import numpy as np

from nnik.report.document import D_UM, D_UNIT, Cell, Fig, Section, Table, finite, fmt, lookup, num, txt
from nnik.report.inputs import FIXED_EVAL_FILE
from nnik.report.measured import target_names, target_status

PNG_ERROR_MAP = "error_map.png"
PNG_ERROR_HIST = "error_hist.png"
PNGS = (PNG_ERROR_MAP, PNG_ERROR_HIST)
GRID_N = 161  # regular grid (per axis) for the float heatmap of an analytic mechanism


def _err_rows(ctx, label: str, vals: dict, keys: dict, note: str = "", note_cls: str = "") -> list[list[Cell]]:
    """One row per output: label | output | max RMS p99 (unit) | phys unit | max RMS p99 | note."""
    rows = []
    for j, o in enumerate(ctx.outputs):
        r = [txt(label, "label", rowspan=ctx.n_out)] if j == 0 else []
        r.append(txt(o))
        for s in ("max", "rms", "p99"):
            v = lookup(vals.get(s), j)
            r.append(num(v, D_UNIT, f"{keys[s]}/{j}" if keys.get(s) and v is not None else None))
        if ctx.phys is not None:
            r.append(txt(ctx.phys.label))
            for s in ("max", "rms", "p99"):
                v = lookup(vals.get(s), j)
                r.append(num(None if v is None else float(v) * ctx.phys.factors[j], ctx.phys.digits,
                             cls="num derived"))
        else:
            r += [txt("—"), num(None, 0), num(None, 0), num(None, 0)]
        if j == 0:
            r.append(txt(note, note_cls, rowspan=ctx.n_out))
        rows.append(r)
    return rows

def _pos_row(ctx, label: str, pos: dict | None, key: str | None, note: str = "") -> list[list[Cell]]:
    if not isinstance(pos, dict):
        return []
    r = [txt(label, "label"), txt("head position"), num(None, 0), num(None, 0), num(None, 0), txt("µm")]
    for s in ("max", "rms", "p99"):
        r.append(num(pos.get(s), D_UM, f"{key}/{s}" if key else None, cls="num" if key else "num derived"))
    r.append(txt(note))
    return [r]

def _nr_row(ctx, label: str, reason: str, cls: str = "notrun") -> list[Cell]:
    text = reason if cls == "bad" or " not run" in reason else f"not run — {reason}"
    return [txt(label, "label"), Cell(text, cls=cls, colspan=9)]

def build(ctx) -> Section:
    m, unit = ctx.m, ctx.unit
    sec = Section("accuracy", "Accuracy")
    ds = m.get("dataset") or {}
    sec.paragraphs.append(
        f"Absolute error against the {ds.get('truth', 'truth')} on {ds.get('n_test', '?')} test points, "
        f"in {unit} and in physical units" + (f" ({ctx.phys.label})" if ctx.phys else "") + ". "
        "Physical values are the output error times the actuator resolution; head position errors "
        "(µm) come from the forward kinematics where the machine has an analytic model.")
    if ctx.phys is None:
        sec.not_run.append(f"physical units not available: {ctx.phys_reason}")
    hdr = ["model", "output", f"max ({unit})", f"RMS ({unit})", f"p99 ({unit})", "physical unit",
           "max", "RMS", "p99", "note"]
    t = Table("accuracy-table", "Error per output: max, RMS, 99th percentile", hdr)
    aff = m.get("affine_only")
    if isinstance(aff, dict):
        t.rows += _err_rows(ctx, "affine least squares (baseline)", {"max": aff.get("max_abs"), "rms": aff.get("rms"),
                                 "p99": aff.get("p99")},
                                 {"max": "affine_only/max_abs", "rms": "affine_only/rms", "p99": "affine_only/p99"},
                                 "a 2×2 map plus offset fitted on the training set")
    fl = m.get("float")
    if isinstance(fl, dict):
        t.rows += _err_rows(ctx, "float64 MLP (host)", {"max": fl.get("max_abs"), "rms": fl.get("rms"),
                                 "p99": fl.get("p99")},
                                 {"max": "float/max_abs", "rms": "float/rms", "p99": "float/p99"},
                                 "torch float64; ONNX checked against it")
        t.rows += _pos_row(ctx, "float64 MLP (host)", fl.get("position_um"), "float/position_um")
    else:
        t.rows.append(_nr_row(ctx, "float64 MLP (host)", "no `float` section in metrics.json"))
    fx = m.get("fixed")
    dfx = ctx.derived_fixed
    delivered_vals = None
    if isinstance(fx, dict):
        t.rows += _err_rows(ctx, "fixed point, integer model (before rounding)",
                                 {"max": fx.get("max_abs"), "rms": fx.get("rms"), "p99": fx.get("p99")},
                                 {"max": "fixed/max_abs", "rms": "fixed/rms", "p99": "fixed/p99"},
                                 f"Python integer model, tanh {fx.get('tanh_variant', '?')}")
        delivered_vals = {"max": fx.get("delivered_max_abs"),
                          "rms": dfx["rms"] if dfx else None, "p99": dfx["p99"] if dfx else None}
        note = "rounded integer commands" + ("" if dfx else f"; RMS/p99 need {FIXED_EVAL_FILE}")
        t.rows += _err_rows(ctx, "fixed point, delivered commands", delivered_vals,
                                 {"max": "fixed/delivered_max_abs"}, note)
        if dfx:
            t.rows += _pos_row(ctx, "fixed point, delivered commands", dfx.get("position_um"), None,
                                    "forward kinematics of the delivered commands")
    else:
        t.rows.append(_nr_row(ctx, "fixed point", "fixed-point export not run: no `fixed` section in metrics.json"))

    def chip_rows(label: str, rec: dict | None, reason: str):
        if rec is None:
            t.rows.append(_nr_row(ctx, label, reason))
        elif not rec.get("bit_exact"):
            t.rows.append(_nr_row(ctx, label, f"NOT bit-exact with the integer model: {rec.get('mismatches', '?')} "
                                              "mismatches; its errors are unknown — do not flash", "bad"))
        elif delivered_vals is None:
            t.rows.append(_nr_row(ctx, label, "bit-exact, but no `fixed` section to take the errors from"))
        else:
            pts = rec.get("points")
            t.rows.extend(_err_rows(ctx, label, delivered_vals, {"max": "fixed/delivered_max_abs"},
                                         "bit-exact with the integer model" + (f" on {pts} points" if pts else "")
                                         + ": the delivered commands above", "good"))

    host = m.get("host")
    chip_rows("C on host", host if isinstance(host, dict) and "not_run" not in host else None,
              host["not_run"] if isinstance(host, dict) and "not_run" in host else "no `host` section in metrics.json")
    for tname in target_names(m):
        tm, reason = target_status(m, tname)
        chip_rows(f"C on {tname}", tm, reason)
    sec.tables.append(t)

    # verdict against the physical limit (DOMAIN: <= 0.5 unit means the rounded command is within 1)
    pre, what = None, None
    if isinstance(fx, dict) and isinstance(fx.get("max_abs"), list):
        pre, what = max(fx["max_abs"]), "fixed-point"
    elif isinstance(fl, dict) and isinstance(fl.get("max_abs"), list):
        pre, what = max(fl["max_abs"]), "float"
    if finite(pre):
        if pre <= 0.5:
            sec.verdicts.append(("good", f"The {what} model's largest error before rounding is "
                                         f"{fmt(pre, D_UNIT)} {unit} ≤ 0.5 {unit}: every rounded command is within 1 "
                                         f"{unit} of the exact one on the test set."))
        else:
            sec.verdicts.append(("bad", f"The {what} model's largest error before rounding is {fmt(pre, D_UNIT)} {unit} "
                                        f"> 0.5 {unit}: some rounded commands are more than 1 {unit} from exact."))
    ctx.plot(sec, lambda: plot_error_map(ctx))
    ctx.plot(sec, lambda: plot_error_hist(ctx))
    return sec

def plot_error_map(ctx) -> Fig | str:
    from nnik.report import plots as rp

    inp, unit = ctx.inp, ctx.unit
    scn = inp.scenario
    ws = scn.workspace if scn is not None else None
    extent = (ws.x_mm[0], ws.x_mm[1], ws.y_mm[0], ws.y_mm[1]) if ws is not None else None
    fe = inp.fixed_eval
    if fe is not None:
        p, err = fe["p_test"], fe["q_fixed"] - fe["q_true"]
        kind = "binned" if len(p) >= 2000 else "points"
        how = "largest |error| per cell over" if kind == "binned" else "at each of"
        title = (f"{ctx.m['name']}: fixed-point model (before rounding) vs {truth_label(ctx.m)}, "
                 f"{how} {len(p)} test points")
        rp.error_map(ctx.out / PNG_ERROR_MAP, x=p[:, 0], y=p[:, 1], err=err, outputs=ctx.outputs, unit=unit,
                     title=title, kind=kind, extent=extent)
        cap = f"Fixed-point error over the workspace ({how} {len(p)} test points); red cross: worst point."
    else:
        if inp.model is None:
            return f"error map not run: {inp.model_reason} and {inp.fixed_eval_reason}"
        if ctx.analytic:
            from nnik.machine.data import exact_targets

            pts = ws.grid(GRID_N)
            err = (inp.model.predict(pts) - exact_targets(scn, pts)).reshape(GRID_N, GRID_N, -1)
            xs = np.linspace(ws.x_mm[0], ws.x_mm[1], GRID_N)
            ys = np.linspace(ws.y_mm[0], ws.y_mm[1], GRID_N)
            title = (f"{ctx.m['name']}: FLOAT64 MLP vs exact IK on a {GRID_N}×{GRID_N} grid "
                     "(fixed-point export not run)")
            rp.error_map(ctx.out / PNG_ERROR_MAP, x=xs, y=ys, err=err, outputs=ctx.outputs, unit=unit,
                         title=title, kind="grid", extent=extent)
            cap = (f"Float64 MLP error on a regular {GRID_N}×{GRID_N} grid (the fixed-point model was not run: "
                   f"{inp.fixed_eval_reason}); red cross: worst point.")
        else:
            if inp.data is None:
                return f"error map not run: {inp.data_reason}"
            p, q = inp.data.p["test"], inp.data.q["test"]
            err = inp.model.predict(p) - q
            title = (f"{ctx.m['name']}: FLOAT64 MLP vs {truth_label(ctx.m)} ({len(p)} points; "
                     "fixed-point export not run)")
            rp.error_map(ctx.out / PNG_ERROR_MAP, x=p[:, 0], y=p[:, 1], err=err, outputs=ctx.outputs,
                         unit=unit, title=title, kind="points", extent=extent)
            cap = (f"Float64 MLP error at the {len(p)} held-out measured points (no analytic model, so no grid; "
                   f"fixed-point model not run: {inp.fixed_eval_reason}); red cross: worst point.")
    return Fig(PNG_ERROR_MAP, "error heatmap over the workspace", cap)

def plot_error_hist(ctx) -> Fig | str:
    from nnik.report import plots as rp

    inp = ctx.inp
    fe = inp.fixed_eval
    if fe is not None:
        errors = {"float64 MLP": fe["q_float"] - fe["q_true"],
                  "fixed point (before rounding)": fe["q_fixed"] - fe["q_true"],
                  "delivered integer commands": fe["q_delivered"] - fe["q_true"]}
        title = f"{ctx.m['name']}: error distribution, float vs fixed point ({len(fe['p_test'])} test points)"
        cap = "Signed error distributions of the float64 MLP, the fixed-point model and the delivered commands."
    else:
        if inp.model is None or inp.data is None:
            return f"error histogram not run: {inp.model_reason or inp.data_reason}"
        p, q = inp.data.p["test"], inp.data.q["test"]
        errors = {"float64 MLP": inp.model.predict(p) - q}
        title = f"{ctx.m['name']}: error distribution, FLOAT64 MLP only (fixed-point export not run)"
        cap = f"Signed error distribution of the float64 MLP only (fixed point not run: {inp.fixed_eval_reason})."
    rp.error_histogram(ctx.out / PNG_ERROR_HIST, errors=errors, outputs=ctx.outputs, unit=ctx.unit, title=title)
    return Fig(PNG_ERROR_HIST, "error histogram", cap)


def truth_label(m: dict) -> str:
    t = lookup(m, "dataset", "truth", default="truth")
    return "exact IK" if t == "analytic IK" else t

