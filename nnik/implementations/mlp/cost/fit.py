"""Least-squares fit of the cost coefficients to the measured calibration networks."""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp.cost.fast_features import fast_path
from nnik.implementations.mlp.cost.features import (cycle_features, flash_features, frame_features, ram_features,
                                                    size_features)
from nnik.implementations.mlp.cost.shifts import shift_offset
from nnik.implementations.mlp.cost.span import span_rows


def lstsq(rows: list[dict], y: np.ndarray, offset: np.ndarray, weights: np.ndarray | None = None) -> tuple[dict, dict]:
    names = sorted({k for r in rows for k in r})
    X = np.array([[r.get(k, 0.0) for k in names] for r in rows], dtype=float)
    t = y - offset
    w = np.ones(len(t)) if weights is None else weights
    sol, *_ = np.linalg.lstsq(X * w[:, None], t * w, rcond=None)
    rank = int(np.linalg.matrix_rank(X))
    pred = X @ sol + offset
    res = y - pred
    return {k: float(v) for k, v in zip(names, sol)}, {"rank": rank, "n_features": len(names), "rows": len(t),
                                                         "max_abs_residual": float(np.abs(res).max()),
                                                         "rms_residual": float(np.sqrt(np.mean(res ** 2))),
                                                         "pred": pred}


FAR_ABOVE = 66  # frame bytes beyond which the locals above the arrays are out of Y+q reach (q <= 63)


def _fit_frame(meas: list[dict]) -> dict | None:
    rows = [(frame_features(m["im"]), m["frame"]) for m in meas if m.get("frame") is not None]
    if not rows:
        return None
    coef, fit = lstsq([r[0] for r in rows], np.array([float(r[1]) for r in rows]), np.zeros(len(rows)))
    pred = fit.pop("pred")
    y = np.array([float(r[1]) for r in rows])
    far_wrong = int(np.sum((pred > FAR_ABOVE) != (y > FAR_ABOVE)))
    return {"coef": _round(coef), "far_above": FAR_ABOVE, "fit": {**fit, "far_misclassified": far_wrong}}


def _envelope(meas: list[dict]) -> dict:
    """Largest hidden size calibrated per code path and number of layers (fast kernel paths)."""
    env: dict = {}
    for m in meas:
        im = m["im"]
        key_path = fast_path(im, m.get("target")) if getattr(im, "kernel", None) == "fast" else "portable"
        key = f"{key_path}:{len(im.hidden)}"
        env[key] = max(env.get(key, 0), max(int(np.asarray(L.W).shape[0]) for L in im.hidden))
    return env


def _far(m: dict) -> bool:
    return m.get("frame") is not None and m["frame"] > FAR_ABOVE


def fit_measurements(meas: list[dict], tables: dict, kern: str | None = None,
                     fixed: dict[str, float] | None = None) -> dict:
    """Least-squares fit of the cost coefficients to the measured calibration networks
    (``fixed``: cycle coefficients measured on their own, e.g. the tanh classes; kept as given)."""
    fixed = fixed or {}
    crow, cy, coff, cw, sizes, models = [], [], [], [], [], []
    frame_model = _fit_frame(meas)
    for m in meas:
        im, vec = m["im"], m["vec"]
        fast = getattr(im, "kernel", None) == "fast"
        far = _far(m)
        feats = cycle_features(im, vec, far=far, target=m.get("target"))
        off = 0.0 if fast else shift_offset(im, tables, "cycles")[0]
        for v in range(len(vec)):
            row = {k: float(a[v]) for k, a in feats.items()}
            crow.append({k: x for k, x in row.items() if k not in fixed})
            cy.append(float(m["cycles"][v]))
            coff.append(off + sum(fixed[k] * x for k, x in row.items() if k in fixed))
            cw.append(1.0 / np.sqrt(len(vec)))  # each network weighs about the same
        foff = 0.0 if fast else shift_offset(im, tables, "bytes")[0]
        sizes.append((size_features(im, far=far, target=m.get("target")), m["flash"], m["ram"], foff))
        models.append({"spec": m["label"], "shape": list(im.shape), "tanh": im.tanh_variant,
                       "cycles_mean": float(np.mean(m["cycles"])), "flash": int(m["flash"]), "ram": int(m["ram"]),
                       "formats": _format_summary(im), "frame": m.get("frame")})
    cy_a, coff_a = np.array(cy), np.array(coff)
    ccoef, cfit = lstsq(crow, cy_a, coff_a, np.array(cw))
    ccoef.update(fixed)
    pred = cfit.pop("pred")
    k0, rel = 0, []
    for m, info in zip(meas, models):
        n = len(m["vec"])
        pm, mm = pred[k0:k0 + n].mean(), cy_a[k0:k0 + n].mean()
        info["cycles_fit"] = round(float(pm), 1)
        rel.append(abs(pm - mm) / mm * 100)
        k0 += n
    cfit["max_rel_error_pct"] = float(max(rel))
    frows = [flash_features(sf) for sf, *_ in sizes]
    fl = np.array([x[1] for x in sizes])
    fo = np.array([x[3] for x in sizes])
    fcoef, ffit = lstsq(frows, fl, fo)
    fpred = ffit.pop("pred")
    ffit["max_rel_error_pct"] = float(np.max(np.abs(fpred - fl) / fl * 100))
    rrows = [ram_features(sf) for sf, *_ in sizes]
    ra = np.array([x[2] for x in sizes])
    rcoef, rfit = lstsq(rrows, ra, np.zeros(len(ra)))
    rfit.pop("pred")
    for info, fp in zip(models, fpred):
        info["flash_fit"] = round(float(fp), 1)
    return {
        "kernel": kern,
        "variants": sorted({m["im"].tanh_variant for m in meas}),
        "cycles": {"coef": _round(ccoef), "fit": cfit},
        "flash": {"coef": _round(fcoef), "fit": ffit},
        "ram": {"coef": _round(rcoef), "fit": rfit},
        "frame": frame_model,
        "envelope": _envelope(meas),
        **({"span_rows": [_round(r) for r in span_rows(meas, _far)]} if kern == "fast" else {}),
        "models": models,
    }


def _round(d: dict) -> dict:
    return {k: round(v, 4) for k, v in sorted(d.items())}


def _format_summary(im) -> dict:
    return {"sh": [int(L.sh) for L in im.hidden], "sat": [bool(L.saturate) for L in im.hidden],
            "g": int(im.out.g), "F": int(im.out.F), "e": 15 + int(im.out.g) - int(im.out.F),
            "K": np.asarray(im.inp.K).tolist(), "S": np.asarray(im.inp.S).tolist()}
