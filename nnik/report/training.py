"""Section: training and the ONNX check, with the training curve."""

from __future__ import annotations

from nnik.report.document import D_SEC, Cell, Fig, Section, Table, num, txt
from nnik.report.inputs import MODEL_FILE

PNG_TRAINING = "training_curve.png"
PNGS = (PNG_TRAINING,)


def build(ctx) -> Section:
    m = ctx.m
    sec = Section("training", "Training and export")
    t = Table("training-table", "Training", ["item", "value"])
    t.rows.append([txt("training time (s)", "key"), num(m.get("train_seconds"), D_SEC, "train_seconds")])
    stop = (m.get("training") or {}).get("stopped_by")
    if stop is not None:
        capped = stop != "budget"
        t.rows.append([txt("stopped by", "key"), Cell(
            "the wall-clock cap ([training] max_seconds): capped, not reproducible" if capped
            else "its iteration budget (reproducible)",
            cls="bad" if capped else "good")])
    hist = list(getattr(ctx.inp.model, "history", None) or [])
    if hist:
        restarts = sorted({int(h["restart"]) for h in hist})
        best = [h for h in hist if h.get("best")]
        t.rows.append([txt("restarts", "key"), num(len(restarts), 0, cls="num derived")])
        if best:
            t.rows.append([txt("best validation MSE (standardised)", "key"),
                           num(min(h["val"] for h in best), "sci", cls="num derived")])
    onnx = m.get("onnx")
    if isinstance(onnx, dict):
        t.rows.append([txt("ONNX vs torch, max |diff|", "key"), num(onnx.get("max_abs_diff"), "sci", "onnx/max_abs_diff")])
        t.rows.append([txt("ONNX tolerance", "key"), num(onnx.get("tolerance"), "sci", "onnx/tolerance")])
        ok = bool(onnx.get("ok"))
        t.rows.append([txt("ONNX check", "key"), Cell("passed" if ok else "FAILED", value=ok, key="onnx/ok",
                                                     cls="good" if ok else "bad")])
    else:
        t.rows.append([txt("ONNX check", "key"), Cell("not run — no `onnx` section in metrics.json", cls="notrun")])
    sec.tables.append(t)
    if ctx.inp.model is None:
        sec.not_run.append(f"training curve not run: {ctx.inp.model_reason}")
    elif not hist:
        sec.not_run.append(f"training curve not run: {MODEL_FILE} holds no training history")
    else:
        ctx.plot(sec, lambda: plot_training(ctx, hist))
    return sec

def plot_training(ctx, hist) -> Fig:
    from nnik.report import plots as rp

    net = ctx.m.get("network") or {}
    rp.training_curve(ctx.out / PNG_TRAINING, history=hist,
                      title=f"{ctx.m['name']}: {'-'.join(map(str, net.get('shape', [])))} MLP, "
                            "Adam then L-BFGS (dot: switch)")
    return Fig(PNG_TRAINING, "training curve", "Train (dashed) and validation (solid) loss against the optimiser "
               "step (Adam steps, then L-BFGS rounds), per restart; the kept restart is thick, its best validation point starred.")
