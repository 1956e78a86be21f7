"""The MLP's host check: its C, instrumented (-DNNIK_INSTRUMENT), against the integer model on
named input sets, with the overflow and saturation counters."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik.implementations.mlp.fixedpoint import IntegerModel
from nnik.targets.host import build_and_run


def verification_inputs(im: IntegerModel, p_test_mm: np.ndarray, n_random: int = 100_000, seed: int = 0) -> dict:
    """Named input sets in um: the test set, random in-domain points, corners/edges, out of domain."""
    lo, hi = im.inp.lo, im.inp.hi
    rng = np.random.default_rng(seed)
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]], dtype=np.int64)
    span = hi - lo
    outside = np.concatenate([
        corners + np.array([[-1, -1], [-1, 1], [1, -1], [1, 1]]),
        corners + np.array([[-1, -1], [-1, 1], [1, -1], [1, 1]]) * span,
        rng.integers(lo - span, hi + span + 1, (2000, 2)),
        np.array([[-(2**31), -(2**31)], [2**31 - 1, 2**31 - 1], [-(2**31), 2**31 - 1]], dtype=np.int64),
    ])
    outside = outside[np.any((outside < lo) | (outside > hi), axis=1)]
    return {
        "test": np.rint(p_test_mm * 1000).astype(np.int64),
        "random": rng.integers(lo, hi + 1, (n_random, 2)),
        "corners": corners,
        "outside": outside,
    }


def run_host(c_dir: Path, name: str, in_um: np.ndarray, cc: str = "gcc") -> dict:
    """Run NAME.c instrumented (-DNNIK_INSTRUMENT) with the MLP check driver: outputs, flags,
    pre-rounding totals and the overflow/saturation counters."""
    defines = ["-DNNIK_INSTRUMENT", f"-DNNIK_MODEL={name}", f'-DNNIK_MODEL_HEADER="{name}.h"']
    lines = build_and_run(c_dir, name, "mlp_check.c", defines, in_um, cc=cc).strip().splitlines()
    tail = lines[-1].split()
    rows = np.array([ln.split() for ln in lines[:-1]], dtype=np.int64).reshape(-1, 5)
    return {"out": rows[:, 0:2], "flags": rows[:, 2], "total": rows[:, 3:5],
            "overflows": int(tail[1]), "saturations": int(tail[3])}


def verify_host(im: IntegerModel, c_dir: Path, inputs: dict) -> dict:
    """Compare C and the integer model on every input set; counts mismatches and instrumented events."""
    summary = {"points": 0, "mismatches": 0, "overflows": {}, "saturations": {}}
    for label, pts in inputs.items():
        c = run_host(c_dir, im.name, pts)
        total, out, flags = im.run(pts)
        bad = np.any(c["out"] != out, axis=1) | (c["flags"] != flags) | np.any(c["total"] != total, axis=1)
        summary["points"] += int(len(pts))
        summary["mismatches"] += int(bad.sum())
        summary["overflows"][label] = c["overflows"]
        summary["saturations"][label] = c["saturations"]
    summary["bit_exact"] = summary["mismatches"] == 0
    return summary
