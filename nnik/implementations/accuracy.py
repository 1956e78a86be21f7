"""Accuracy of an implementation's integer model on the problem's check set, in output units."""

from __future__ import annotations

import numpy as np

from nnik.implementations.base import Implementation


def accuracy(impl: Implementation, subset: tuple[np.ndarray, np.ndarray] | None = None) -> dict:
    """Pre-rounding and delivered error against the exact IK (or held-out rows) on the dense
    check grid (or on ``subset`` = (points, truth)): ``pre_max_abs``/``rms`` per output,
    ``pre_max`` (worst output), delivered max; for a measured machine, ``claimed_max``: the max
    error against the machine the bootstrap of its reference supports at these points
    (nnik.machine.ref_claim)."""
    pts, truth = impl.problem.check if subset is None else subset
    r = impl.run(pts)
    err = r.pre - truth
    d = r.out - truth
    ref = impl.problem.reference
    claim = {} if ref is None else {"claimed_max": ref.claim(impl.problem.to_mm(pts), err)}
    return {"points": int(len(pts)), **claim,
            "pre_max_abs": np.abs(err).max(0).tolist(),
            "pre_max": float(np.abs(err).max()),
            "rms": np.sqrt((err**2).mean(0)).tolist(),
            "delivered_max_abs": np.abs(d).max(0).tolist()}
