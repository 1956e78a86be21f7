"""Section: the integer tanh, its error beside published figures, and its error plot."""

from __future__ import annotations

import importlib

import numpy as np

from nnik.report.document import D_LSB, Fig, Section, Table, lookup, not_run_cell, num, txt
from nnik.report.inputs import short_exc

PNG_TANH = "tanh_error.png"
PNGS = (PNG_TANH,)
Q15 = 32768.0
PUB_TANH = (  # (source, what, value, unit)
    ("seed 000 (CBA 2012), eq. 10-14", "piecewise degree-5 polynomials, float RMS", 1.7362e-5, "abs"),
    ("CMSIS-NN / TFLM int16 table + interpolation", "max error", 1.48, "LSB"),
    ("AIfES Q7 PLAN tanh", "max error", 0.038, "abs"),
    ("256-entry table indexed by Q3.4", "max error", 0.063, "abs"),
)


def build(ctx) -> Section:
    m = ctx.m
    sec = Section("tanh", "Integer tanh")
    th = m.get("tanh") if isinstance(m.get("tanh"), dict) else None
    variant = (th or {}).get("variant") or lookup(m, "fixed", "tanh_variant")
    try:
        act = importlib.import_module("nnik.implementations.mlp.tanh")  # optional here
    except Exception as exc:  # noqa: BLE001
        act, act_reason = None, f"nnik.implementations.mlp.tanh could not be imported ({short_exc(exc)})"
    else:
        act_reason = ""
        for need in ("tanh_int", "VARIANTS", "sweep"):
            if not hasattr(act, need):
                act, act_reason = None, f"nnik.implementations.mlp.tanh has no `{need}`"
                break
    default_used = False
    if variant is None and act is not None:
        variant = getattr(act, "DEFAULT_VARIANT", None) or next(iter(act.VARIANTS), None)
        default_used = True
    t = Table("tanh-table", "tanh replacement: error in LSB of Q15 (1 LSB = 2⁻¹⁵ ≈ 3.05e-5)",
              ["source", "variant", "max (LSB)", "RMS (LSB)", "note"])
    if th is not None:
        t.rows.append([txt("this run (metrics.json)", "label"), txt(th.get("variant")),
                       num(th.get("max_lsb"), D_LSB, "tanh/max_lsb"), num(th.get("rms_lsb"), D_LSB, "tanh/rms_lsb"),
                       txt("all 65536 int16 inputs")])
    else:
        t.rows.append([txt("this run (metrics.json)", "label"),
                       not_run_cell("no `tanh` section in metrics.json", 4)])
    var_obj = None
    if act is not None and variant is not None:
        try:
            var_obj = act.VARIANTS[variant]
            sw = act.sweep(variant)
            note = "recomputed now by nnik.implementations.mlp.tanh.sweep"
            if default_used:
                note += " for the default variant (no variant named in metrics.json)"
            t.rows.append([txt("recomputed", "label"), txt(variant), num(sw.get("max_lsb"), D_LSB, cls="num derived"),
                           num(sw.get("rms_lsb"), D_LSB, cls="num derived"), txt(note)])
        except Exception as exc:  # noqa: BLE001
            var_obj = None
            act_reason = f"variant {variant!r} not available in nnik.implementations.mlp.tanh ({short_exc(exc)})"
    for src, what, val, u in PUB_TANH:
        lsb = val if u == "LSB" else val * Q15
        t.rows.append([txt(f"published: {src}", "published"), txt(what), num(lsb, D_LSB, cls="num derived published"),
                       num(None, 0), txt(f"as published: {val:g}" + (" (absolute)" if u == "abs" else " LSB"))])
    t.note = "Published rows are converted to LSB of Q15 here (absolute × 32768); labelled published."
    sec.tables.append(t)
    if act is None:
        sec.not_run.append(f"tanh error plot not available: {act_reason}")
    elif var_obj is None:
        sec.not_run.append(f"tanh error plot not available: {act_reason or 'no variant to plot'}")
    else:
        ctx.plot(sec, lambda: plot_tanh(ctx, act, variant, var_obj, default_used))
    return sec

def plot_tanh(ctx, act, variant: str, var_obj, default_used: bool) -> Fig:
    from nnik.report import plots as rp

    v = np.arange(-32768, 32768, dtype=np.int64)
    x = v / 4096.0
    ex = np.tanh(x)
    int_err = np.asarray(act.tanh_int(v, variant), dtype=np.float64) - ex * Q15
    if hasattr(act, "tanh_float"):
        fl = np.asarray(act.tanh_float(x, variant), dtype=np.float64)
    else:  # no float pieces exposed: the integer result is all there is
        fl = np.asarray(act.tanh_int(v, variant), dtype=np.float64) / Q15
    float_err = (fl - ex) * Q15
    desc = getattr(var_obj, "description", "")
    title = f"tanh replacement {variant}" + (" (default variant)" if default_used else "")
    if desc:
        title += f"\n{desc}"
    rp.tanh_error(ctx.out / PNG_TANH, x=x, float_err_lsb=float_err, int_err_lsb=int_err, title=title,
                  sat_x=getattr(var_obj, "sat_x", None))
    return Fig(PNG_TANH, "tanh approximation error", f"Error of {variant} over its whole Q3.12 input range, "
               "float pieces and integer implementation, in LSB of Q15.")
