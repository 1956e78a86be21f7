"""Calibrate the ``lut``/``hybrid`` cost model (:mod:`nnik.implementations.lut.cost`) on the
simulators:  python -m nnik.implementations.lut.calibrate [lut|hybrid ...]

Reference configurations use deterministic synthetic tables (the emitted C depends on the
generator only, not on data or fitting), so the calibration's key -- the hash of their C --
changes only when the C does. The first ones fit (a, b); the rest validate the fit.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from nnik.implementations.lut.cost import CALIBRATION, TOLERANCE, load, static_counts
from nnik.implementations.lut.reference import REFERENCES, reference_hash, reference_impl

def _cls(family: str):
    from nnik.implementations import family as fam

    return fam(family)


def _linfit(x, y):
    m = np.column_stack([np.ones(len(x)), x])
    return [float(v) for v in np.linalg.lstsq(m, np.asarray(y, float), rcond=None)[0]]


def calibrate(family: str, n_inside: int = 60) -> dict:
    from nnik.progress import bar

    from nnik.errors import NnikError
    from nnik.implementations.verify import verify_on_target

    rows = {"avr": [], "pic18": []}
    refs = REFERENCES[family]
    with tempfile.TemporaryDirectory() as tmp:
        for i, (scenario, cfg, role) in enumerate(bar(refs, desc=f"calibrating {family}")):
            im = reference_impl(_cls(family), scenario, cfg)
            for target in rows:
                r = verify_on_target(im, target, Path(tmp) / f"c{i}", Path(tmp) / f"w{i}{target}", n_inside=n_inside)
                if "not_run" in r:
                    raise NnikError(f"{target}: {r['not_run']}")
                if r["mismatches"]:
                    raise NnikError(f"{family} reference {i} ({scenario}) is not bit-exact on {target}")
                cyc, code = static_counts(im, target)
                rows[target].append({"scenario": scenario, "config": cfg, "role": role, "static_cycles": cyc,
                                     "static_bytes": code, "cycles": r["cycles"],
                                     "flash_bytes": r["flash_bytes"] - im.model_bytes(), "ram": r["ram_bytes"]})
    out = {"family": family, "key": reference_hash(_cls(family)), "tolerance": TOLERANCE, "targets": {}}
    for target, rs in rows.items():
        fit = [r for r in rs if r["role"] == "fit"]
        val = [r for r in rs if r["role"] == "validate"]
        cyc = _linfit([r["static_cycles"] for r in fit], [r["cycles"] for r in fit])
        fl = _linfit([r["static_bytes"] for r in fit], [r["flash_bytes"] for r in fit])
        for r in rs:
            r["cycles_pred"] = cyc[0] + cyc[1] * r["static_cycles"]
            r["flash_pred"] = fl[0] + fl[1] * r["static_bytes"]
            r["cycles_rel_err"] = abs(r["cycles_pred"] - r["cycles"]) / r["cycles"]
            r["flash_rel_err"] = abs(r["flash_pred"] - r["flash_bytes"]) / r["flash_bytes"]
        worst = max(max(r["cycles_rel_err"], r["flash_rel_err"]) for r in val)
        out["targets"][target] = {"cycles": cyc, "flash": fl, "ram": int(max(r["ram"] for r in rs)),
                                  "validation_max_rel_err": worst, "validated": bool(worst <= TOLERANCE),
                                  "runs": rs}
    return out


def main(argv: list[str]) -> int:
    for family in argv or ["lut", "hybrid"]:
        cal = calibrate(family)
        (CALIBRATION / f"{family}.json").write_text(json.dumps(cal, indent=1) + "\n")
        load.cache_clear()
        for t, c in cal["targets"].items():
            print(f"{family} {t}: cycles {c['cycles'][0]:.1f} + {c['cycles'][1]:.4f} x static, "
                  f"validation max error {100 * c['validation_max_rel_err']:.2f} % -> "
                  f"{'validated' if c['validated'] else 'NOT validated'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
