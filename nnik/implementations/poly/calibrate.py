"""Developer tool: calibrate the poly family's cost model on simavr and gpsim.

    python -m nnik.implementations.poly.calibrate      (about 2.5 minutes)

Measures the reference configurations (the fit) and the validation configurations (the check,
within TOLERANCE) of :mod:`nnik.implementations.poly.cost` and writes nnik/calibration/poly.json,
keyed to the hash of the reference configurations' C. The wide path (width 32) is calibrated
by ``python3 -m nnik.bench.poly32_calibration``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnik.implementations.poly.family import PolyImpl
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
    kept = _checks_still_valid(out, targets)
    if kept:
        cal["check"] = {"targets": kept}
    out.write_text(json.dumps(cal, indent=1) + "\n")
    _STATE.pop("cal", None)
    return cal


def _checks_still_valid(path: Path, targets: dict) -> dict:
    """The recorded checks (nnik.bench.costs --record) of the targets whose model this calibration
    left unchanged; a target whose coefficients moved states no band until it is checked again."""
    if not path.exists():
        return {}
    prev = json.loads(path.read_text())
    def unchanged(t: str) -> bool:
        a, b = prev.get("targets", {}).get(t, {}).get("cycles", []), targets[t]["cycles"]
        return len(a) == len(b) and bool(np.allclose(a, b, rtol=1e-9, atol=1e-6))

    same = [t for t in targets if unchanged(t)]
    return {t: s for t, s in ((prev.get("check") or {}).get("targets") or {}).items() if t in same}


if __name__ == "__main__":
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        res = calibrate(Path(tmp))
    print(f"validated: {res['validated']} (worst validation error {100 * res['max_validation_error']:.2f} %)")
