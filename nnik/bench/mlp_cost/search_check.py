"""The estimator on the networks `nnik search` can propose: random architectures of its MLP space
(one or two hidden layers of the search's widths, full or residual, int8 or int16 weights, the
fast kernel it always uses), predicted against simavr and gpsim.

The calibration and the recorded sweep are judged on full networks of the galvo; the search also
prices residual networks with an affine base. What the estimator states about its own cycle error
(``estimate()["cycles_error_pct"]``) is the larger of the recorded sweep's and this check's,
recorded per profile in the calibration file (``python3 -m nnik.bench.mlp_cost search-check --record``)
with a margin for draws the check has not seen."""

from __future__ import annotations

import datetime
import json
import math
import sys
from pathlib import Path

import numpy as np

from nnik.implementations.mlp.cost.calibrations import BUILTIN_PROFILES, REPO_ROOT, cal_path, forget_loaded
from nnik.implementations.mlp.cost.synthetic import SEARCH_TANHS as TANHS  # noqa: F401 - re-exported
from nnik.implementations.mlp.cost.synthetic import SEARCH_WIDTHS as WIDTHS  # noqa: F401 - re-exported
from nnik.implementations.mlp.cost.synthetic import CalSpec, draw_specs  # noqa: F401 - draw_specs re-exported

CHECK_DIR = REPO_ROOT / "build" / "estimator_search_check"
MARGIN_PCT = 0.5  # added to the worst error seen, for the architectures no check has drawn
KERNEL = "fast"


def check(specs: list[CalSpec], profiles: list[str], n_vec: int = 60, workdir: Path = CHECK_DIR,
          verbose: bool = True, only_validated: bool = False) -> list[dict]:
    """Estimate and measure every spec on every profile: rows with the cycle error in % and the
    error the estimate states about itself (``only_validated``: an estimate that states none is
    not measured; its row has no cycles_meas)."""
    from nnik.implementations.mlp.cost.kernels import write_c
    from nnik.bench.mlp_cost.measure import run_profile
    from nnik.implementations.mlp.cost.predict import estimate
    from nnik.implementations.mlp.cost.synthetic import in_domain_vectors, synthetic_model

    rows = []
    for sp in specs:
        im = synthetic_model(sp, kernel=KERNEL)
        d = Path(workdir) / sp.label.replace(":", "_")
        csrc = write_c(im, d / "c", kernel=KERNEL)
        vec = in_domain_vectors(im, n_vec, seed=sp.seed)
        for prof in profiles:
            target = BUILTIN_PROFILES[prof]["target"]
            est = estimate(im, target, prof, kernel=KERNEL)
            if only_validated and not est["validated"]:
                rows.append({"spec": sp.label, "profile": prof, "validated": False,
                             "stated_pct": est.get("cycles_error_pct"), "cycles_pred": round(est["cycles"], 1)})
                continue
            r = run_profile(prof, csrc, im.name, vec, im.shape[-1], d / prof)
            meas = float(r["cycles_mean"])
            row = {"spec": sp.label, "profile": prof, "mode": "full" if sp.scenario == "galvo" else "residual",
                   "cycles_pred": round(est["cycles"], 1), "cycles_meas": meas,
                   "cycles_err_pct": round(100 * (est["cycles"] - meas) / meas, 2),
                   "stated_pct": est.get("cycles_error_pct"), "validated": est["validated"]}
            rows.append(row)
            if verbose:
                print(f"{row['spec']:48s} {prof:11s} {row['cycles_pred']:8.0f} vs {meas:8.0f} "
                      f"({row['cycles_err_pct']:+.2f} %, stated ±{row['stated_pct']})", file=sys.stderr, flush=True)
    return rows


def band(worst_pct: float) -> float:
    """The band a check's worst |error| supports: plus MARGIN_PCT, rounded up to 0.1 %."""
    return math.ceil(10 * (worst_pct + MARGIN_PCT) - 1e-9) / 10


def record(rows: list[dict], seed: int) -> dict:
    """Store, per profile, the worst error of the check (plus MARGIN_PCT) on the networks whose
    estimate is validated (the others state no error) as what the estimator states about the fast
    kernel's cycles."""
    out = {}
    for prof in sorted({r["profile"] for r in rows if r["validated"]}):
        rr = [r for r in rows if r["profile"] == prof and r["validated"]]
        worst = max(abs(r["cycles_err_pct"]) for r in rr)
        s = {"networks": len(rr), "seed": seed, "max_abs_cycles_err_pct": worst,
             "mean_abs_cycles_err_pct": round(float(np.mean([abs(r["cycles_err_pct"]) for r in rr])), 2),
             "stated_cycles_err_pct": band(worst),
             "residual_networks": sum(r["mode"] == "residual" for r in rr),
             "int8_networks": sum(":w8:" in r["spec"] for r in rr),
             "two_layer_networks": sum(r["spec"].split(":")[1].count("-") == 3 for r in rr),
             "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
             "command": "python3 -m nnik.bench.mlp_cost search-check --record"}
        path = cal_path(prof)
        cal = json.loads(path.read_text())
        cal.setdefault("search_check", {})[KERNEL] = s
        path.write_text(json.dumps(cal, indent=1) + "\n")
        out[prof] = s
    forget_loaded()
    return out
