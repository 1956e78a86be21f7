"""Is a network inside what the fast kernel's calibration measured?

The cycle model is linear in constant per-call counts (fast_features).  Least squares
determines it only along the directions the calibration networks span: counts that always
occurred together there (say, an output stage with a positive shift only in residual networks)
are split between their coefficients arbitrarily.  A network whose counts leave that span is an
extrapolation, however close its shape is to a calibrated one.  The calibration stores each
network's counts (``span_rows``); an estimate is validated only when the network's counts are
a linear combination of them (the part of its count vector outside their row space is below
SPAN_TOL of its length).
"""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp.cost.fast_features import fast_counts_prefixed

SPAN_TOL = 1e-6


def structure_row(im, far: bool, target: str | None) -> dict[str, float]:
    """The constant per-call cycle counts of a fast-kernel network (prefixed by its code path)."""
    return fast_counts_prefixed(im, far, target)


def span_rows(meas: list[dict], far_of) -> list[dict[str, float]]:
    """One count row per calibration network (deduplicated, in order)."""
    rows, seen = [], set()
    for m in meas:
        r = structure_row(m["im"], far_of(m), m.get("target"))
        key = tuple(sorted(r.items()))
        if key not in seen:
            seen.add(key)
            rows.append(r)
    return rows


def outside_span(row: dict[str, float], rows: list[dict[str, float]]) -> list[str]:
    """The counts (largest first) that put `row` outside the span of `rows`; [] when inside."""
    names = sorted({k for r in rows for k in r} | set(row))
    if not rows:
        return sorted(row)
    X = np.array([[r.get(k, 0.0) for k in names] for r in rows], dtype=float)
    x = np.array([row.get(k, 0.0) for k in names], dtype=float)
    _, S, Vt = np.linalg.svd(X, full_matrices=False)
    V = Vt[S > 1e-9 * S[0]]
    res = x - V.T @ (V @ x)
    if np.linalg.norm(res) <= SPAN_TOL * max(np.linalg.norm(x), 1.0):
        return []
    order = np.argsort(-np.abs(res))
    return [names[i] for i in order if abs(res[i]) > SPAN_TOL * max(np.linalg.norm(x), 1.0)][:4]
