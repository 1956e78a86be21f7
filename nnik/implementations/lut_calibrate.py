"""Calibrate the ``lut``/``hybrid`` cost model (:mod:`nnik.implementations.lut_cost`) on the
simulators:  python -m nnik.implementations.lut_calibrate [lut|hybrid ...]

Reference configurations use deterministic synthetic tables (the emitted C depends on the
generator only, not on data or fitting), so the calibration's key -- the hash of their C --
changes only when the C does. The first ones fit (a, b); the rest validate the fit.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tempfile
from functools import lru_cache
from pathlib import Path

import numpy as np

from nnik.implementations.lut_cost import CALIBRATION, TOLERANCE, load, static_counts
from nnik.implementations.lut_table import Grid, Table

ROOT = Path(__file__).resolve().parents[2]

# (scenario, config, role)
REFERENCES = {
    "lut": [
        ("galvo_cba2012", {"k": [14, 14], "bits": 16, "W": 16, "symmetry": True}, "fit"),
        ("galvo_cba2012", {"k": [13, 13], "bits": 32, "W": 8, "symmetry": True}, "fit"),
        ("corexy_nonlinear", {"k": [14, 14], "bits": 16, "W": 16, "symmetry": False}, "fit"),
        ("galvo_dual_xy2", {"k": [16, 16], "bits": 32, "W": 16, "symmetry": True}, "fit"),
        ("galvo_cba2012", {"k": [15, 15], "bits": 16, "W": 8, "symmetry": True}, "validate"),
        ("corexy_nonlinear", {"k": [13, 13], "bits": 32, "W": 8, "symmetry": False}, "validate"),
        ("galvo_dual_xy2", {"k": [15, 14], "bits": 16, "W": 16, "symmetry": False}, "validate"),
    ],
    "hybrid": [
        ("corexy_nonlinear", {"k": [14, 14], "bits": 16, "W": 16}, "fit"),
        ("hbot_unicamp", {"k": [16, 16], "bits": 16, "W": 8}, "fit"),
        ("galvo_dual_xy2", {"k": [15, 15], "bits": 32, "W": 16}, "fit"),
        ("corexy_nonlinear", {"k": [13, 13], "bits": 16, "W": 8}, "fit"),
        ("corexy_nonlinear", {"k": [15, 15], "bits": 32, "W": 16}, "validate"),
        ("galvo_cba2012", {"k": [14, 14], "bits": 16, "W": 16}, "validate"),
    ],
}


def _problem(scenario: str):
    from nnik.implementations.problem import Problem
    from nnik.scenario import load_scenario

    scn = load_scenario(ROOT / "datasets" / f"{scenario}.toml")
    return Problem(scn, None, unit_um=scn.export["input_unit_um"])


def reference_impl(family: str, scenario: str, cfg: dict):
    """An implementation with a deterministic synthetic table (and base)."""
    from nnik.implementations.hybrid import HybridImpl
    from nnik.implementations.lut import LutImpl, fold_plan

    p = _problem(scenario)
    rng = np.random.default_rng(sum(cfg["k"]) * 7 + cfg["bits"] + cfg["W"])
    sym = cfg.get("symmetry", False) and family == "lut"
    fold, odd = fold_plan(p, sym)
    grid = Grid.make(p.lo, p.hi, cfg["k"], fold, cfg["W"])
    ny, nx = grid.n[1], grid.n[0]
    ent = np.cumsum(np.cumsum(rng.integers(-300, 301, (2, ny, nx)), axis=1), axis=2) // 4
    ent = np.clip(ent, -12000, 12000)
    if cfg["bits"] == 32:
        ent = ent * 3 + 70000
    offs = tuple(0 if odd[o].any() else 5 + 11 * o for o in range(2))
    tab = Table(grid=grid, bits=cfg["bits"], fb=(8, 6), offset=offs, odd=odd, ent=ent.astype(np.int64))
    full = {**cfg, "fit": "lsq"}
    if family == "lut":
        return LutImpl(p, full, tab)
    tab.offset = (0, 0)
    base = np.array([[12345 << 4, 211, -187], [-777 << 4, -95, 250]], dtype=np.int64)
    return HybridImpl(p, {**full, "base": "affine"}, tab, base, np.array([12, 13]), np.array([100, -40]))


@lru_cache(maxsize=None)
def reference_hash(family: str) -> str:
    h = hashlib.sha256()
    for scenario, cfg, _ in REFERENCES[family]:
        h.update(reference_impl(family, scenario, cfg).render_source().encode())
    return h.hexdigest()[:16]


def _linfit(x, y):
    m = np.column_stack([np.ones(len(x)), x])
    return [float(v) for v in np.linalg.lstsq(m, np.asarray(y, float), rcond=None)[0]]


def calibrate(family: str, n_inside: int = 60) -> dict:
    from tqdm import tqdm

    from nnik.errors import NnikError
    from nnik.implementations.verify import verify_on_target

    rows = {"avr": [], "pic18": []}
    refs = REFERENCES[family]
    with tempfile.TemporaryDirectory() as tmp:
        for i, (scenario, cfg, role) in enumerate(tqdm(refs, desc=f"calibrating {family}")):
            im = reference_impl(family, scenario, cfg)
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
    out = {"family": family, "key": reference_hash(family), "tolerance": TOLERANCE, "targets": {}}
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
