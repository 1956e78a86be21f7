"""Reference configurations of the lut/hybrid cost model: deterministic synthetic tables, so
the emitted C depends on the generator only (not on data or fitting), and the hash that keys
the calibration changes only when the C (or a harness or runtime header) does."""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

import numpy as np

from nnik.implementations.lut.table import Grid, Table, base_terms, dependence, fold_plan

ROOT = Path(__file__).resolve().parents[3]

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
        ("galvo_cba2012", {"k": [13, 13], "bits": 16, "W": 16, "symmetry": True, "separable": True}, "fit"),
        ("galvo_dual_xy2", {"k": [15, 15], "bits": 16, "W": 8, "symmetry": True, "separable": True}, "validate"),
    ],
}


def _problem(scenario: str):
    from nnik.implementations.problem import Problem
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(ROOT / "datasets" / f"{scenario}.toml")
    return Problem(scn, None, unit_um=scn.export["input_unit_um"])


def reference_impl(cls, scenario: str, cfg: dict):
    """An implementation of class `cls` (lut or hybrid) with a deterministic synthetic table
    (and base)."""
    family = cls.family
    p = _problem(scenario)
    rng = np.random.default_rng(sum(cfg["k"]) * 7 + cfg["bits"] + cfg["W"])
    sym = cfg.get("symmetry", False)
    fold, odd = fold_plan(p, sym)
    grid = Grid.make(p.lo, p.hi, cfg["k"], fold, cfg["W"])
    ny, nx = grid.n[1], grid.n[0]
    ent = np.cumsum(np.cumsum(rng.integers(-300, 301, (2, ny, nx)), axis=1), axis=2) // 4
    ent = np.clip(ent, -12000, 12000)
    if cfg["bits"] == 32:
        ent = ent * 3 + 70000
    offs = tuple(0 if odd[o].any() else 5 + 11 * o for o in range(2))
    dep = dependence(p, cfg.get("separable", family == "lut"))
    for o in range(2):  # a 1-D output: replicated along the other axis
        if dep[o] == "y":
            ent[o] = ent[o][:, :1]
        elif dep[o] == "x":
            ent[o] = ent[o][:1, :]
    tab = Table(grid=grid, bits=cfg["bits"], fb=(8, 6), offset=offs, odd=odd, ent=ent.astype(np.int64), dep=dep)
    full = {**cfg, "fit": "lsq"}
    if family == "lut":
        return cls(p, full, tab)

    tab.offset = (0, 0)
    wide = 10 if cfg["W"] == 16 else 1  # 16-bit and 8-bit base slopes
    base = np.array([[12345 << 4, 211 * wide, -187 * wide], [-777 << 4, -95 * wide, 250 * wide]], dtype=np.int64)
    base[~base_terms(odd, dep)] = 0  # the terms a folded or 1-D residual allows
    return cls(p, {**full, "base": "affine"}, tab, base, np.array([12, 13]), np.array([100, -40]))


HARNESS = ("codegen/harness/avr", "codegen/harness/pic18", "codegen/harness/nnik_stub_model.c",
           "codegen/runtime/nnik_flash.h", "codegen/runtime/nnik_kernel.h")


@lru_cache(maxsize=None)
def reference_hash(cls) -> str:
    """Hash of the reference configurations' C (family of class `cls`), the simulator harnesses
    and the runtime headers."""
    h = hashlib.sha256()
    for scenario, cfg, _ in REFERENCES[cls.family]:
        h.update(reference_impl(cls, scenario, cfg).render_source().encode())
    for rel in HARNESS:
        base = ROOT / rel
        for f in sorted(base.rglob("*")) if base.is_dir() else [base]:
            if f.is_file() and f.suffix in (".c", ".h"):
                h.update(f.relative_to(ROOT).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]
