"""Developer tool: calibrate the poly family's cost model on simavr and gpsim.

    python -m nnik.implementations.poly.calibrate      (about 2.5 minutes)
    python -m nnik.implementations.poly.calibrate --wide [--refit LOG]   (the wide path: about 8 minutes)

Measures the reference configurations (the fit) and the validation configurations (the check,
within TOLERANCE) of :mod:`nnik.implementations.poly.cost` and writes nnik/calibration/poly.json,
keyed to the hash of the reference configurations' C. ``--wide``: the wide path's
(width 32) reference configurations, fitted linear in nnik.implementations.poly.wide's counts,
into nnik/calibration/poly32.json with each point's leave-one-out error.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnik.implementations.poly.family import PolyImpl
from nnik.implementations.poly.wide import CALIBRATION as WIDE_CALIBRATION
from nnik.implementations.poly.wide import FEATURES as WIDE_FEATURES
from nnik.implementations.poly.wide import counts as wide_counts
from nnik.implementations.poly.cost import (_STATE, CALIBRATION, FEATURES, FLASH_FEATURES, REFERENCE, TOLERANCE,
                                            VALIDATION, _predict, counts, reference_impl, reference_key)


def _measure(impl, target: str, workdir: Path) -> dict:
    from nnik.implementations.verify import verify_on_target

    r = verify_on_target(impl, target, workdir / "c", workdir / target, n_inside=64)
    if r.get("mismatches"):
        raise RuntimeError(f"{impl.describe()}: {r['mismatches']} mismatches on {target}")
    return r


def calibrate(workdir: Path, out: Path = CALIBRATION) -> dict:
    from nnik.progress import bar

    rows = {"ref": [], "val": []}
    for kind, lst in (("ref", REFERENCE), ("val", VALIDATION)):
        for i, (name, unit, cfg) in enumerate(bar(lst, desc=f"poly {kind}")):
            im = reference_impl(PolyImpl, name, unit, cfg)
            row = {"scenario": name, "unit": unit, "config": cfg, "c_hash": im.source_hash()}
            for t in FEATURES:
                r = _measure(im, t, workdir / f"{kind}{i}")
                row[t] = {"cycles": r["cycles"], "flash_bytes": r["flash_bytes"], **counts(im, t)}
            rows[kind].append(row)
    targets, worst = {}, 0.0
    for t in FEATURES:
        def fit(feats, y_key):
            x = np.array([[1.0] + [r[t][f] for f in feats] for r in rows["ref"]])
            y = np.array([r[t][y_key] for r in rows["ref"]])
            return np.linalg.lstsq(x, y, rcond=None)[0].tolist()
        targets[t] = {"cycles": fit(FEATURES[t], "cycles"), "flash": fit(FLASH_FEATURES[t], "flash_bytes")}
        for r in rows["val"]:
            pred = _predict(targets[t]["cycles"], r[t], FEATURES[t])
            r[t]["predicted_cycles"] = pred
            r[t]["rel_error"] = abs(pred - r[t]["cycles"]) / r[t]["cycles"]
            r[t]["predicted_flash"] = _predict(targets[t]["flash"], r[t], FLASH_FEATURES[t])
            worst = max(worst, r[t]["rel_error"])
    cal = {"key": reference_key(PolyImpl), "targets": targets, "reference": rows["ref"], "validation": rows["val"],
           "max_validation_error": worst, "tolerance": TOLERANCE, "validated": worst <= TOLERANCE}
    out.write_text(json.dumps(cal, indent=1) + "\n")
    _STATE.pop("cal", None)
    return cal



# ---- the wide path (width 32) ---------------------------------------------------------------

# (scenario, config): shipped scenarios, degrees across the wide ladder
WIDE_REFERENCE = [
    ("galvo_dual_xy2", {"degree": 3}),
    ("galvo_dual_xy2", {"degree": 5}),
    ("galvo_dual_xy2", {"degree": 7}),
    ("galvo_cba2012", {"degree": 5}),
    ("galvo_cba2012", {"degree": 9}),
    ("corexy_nonlinear", {"degree": 4}),
    ("corexy_nonlinear", {"degree": 2}),
    ("hbot_unicamp", {"degree": 3}),
]
WIDE = {"width": 32, "coef_bits": 32, "fit": "best", "split": False, "lsb": False, "trim": 4, "rounding": True}
WIDE_TOLERANCE = 0.05  # leave-one-out prediction error that counts as validated


def measure_wide(workdir: Path, only=None) -> list[dict]:
    from nnik.implementations.verify import verify_on_target

    rows = []
    for k, (scn, cfg) in enumerate(WIDE_REFERENCE):
        if only is not None and k not in only:
            continue
        im = reference_impl(PolyImpl, scn, None, {**WIDE, **cfg})
        row = {"scenario": scn, "config": cfg, **wide_counts(im)}
        for t in ("avr", "pic18"):
            r = verify_on_target(im, t, workdir / f"c{k}{t}", workdir / f"w{k}{t}")
            if not r.get("bit_exact"):
                raise SystemExit(f"{scn} {cfg} on {t}: not bit-exact ({r})")
            row[t] = {"cycles": float(r["cycles"]), "flash_bytes": int(r["flash_bytes"])}
        print(json.dumps(row), flush=True)
        rows.append(row)
    return rows


def fit_wide(rows: list[dict]) -> dict:
    x = np.array([[1.0] + [r[f] for f in WIDE_FEATURES] for r in rows])
    out = {}
    worst = 0.0
    for t in ("avr", "pic18"):
        out[t] = {}
        for key, what in (("cycles", "cycles"), ("flash", "flash_bytes")):
            y = np.array([r[t][what] for r in rows])
            coef, *_ = np.linalg.lstsq(x, y, rcond=None)
            out[t][key] = coef.tolist()
            for i in range(len(rows)):  # leave one out
                keep = np.arange(len(rows)) != i
                c, *_ = np.linalg.lstsq(x[keep], y[keep], rcond=None)
                worst = max(worst, abs(float(x[i] @ c) / y[i] - 1))
    return {"targets": out, "loo_max_rel_error": float(worst), "validated": bool(worst <= WIDE_TOLERANCE)}


def calibrate_wide(refit_log: Path | None = None) -> dict:
    """Measure (or, from a measuring run's printed rows, refit) the wide path's cost model and
    write nnik/calibration/poly32.json with every measurement."""
    import tempfile

    if refit_log is not None:
        rows = [json.loads(line) for line in refit_log.read_text().splitlines() if line.startswith("{")]
    else:
        with tempfile.TemporaryDirectory(prefix="nnik-poly32-") as d:
            rows = measure_wide(Path(d))
    cal = {**fit_wide(rows), "features": list(WIDE_FEATURES), "measurements": rows,
           "how": "python -m nnik.implementations.poly.calibrate --wide (simavr -Os, gpsim SDCC)"}
    WIDE_CALIBRATION.write_text(json.dumps(cal, indent=1) + "\n")
    return cal


if __name__ == "__main__":
    import sys
    import tempfile

    if "--wide" in sys.argv:  # [--refit LOG]
        log = Path(sys.argv[sys.argv.index("--refit") + 1]) if "--refit" in sys.argv else None
        res = calibrate_wide(log)
        print(f"wrote {WIDE_CALIBRATION}: leave-one-out max error {100 * res['loo_max_rel_error']:.1f} %")
        sys.exit(0)
    with tempfile.TemporaryDirectory() as tmp:
        res = calibrate(Path(tmp))
    print(f"validated: {res['validated']} (worst validation error {100 * res['max_validation_error']:.2f} %)")
