"""Recursive least squares, the seed's identification method: the estimate after each sample.

theta[k] = theta[k-1] + g[k] (y[k] - phi[k]' theta[k-1]),  g[k] = P phi / (lambda + phi' P phi),
P[k] = (P - g phi' P) / lambda.

With lambda = 1 and P0 = delta I, the estimate after the last sample is the batch least squares
estimate regularised by |theta|^2 / delta; nnik starts from DELTA = 1e8, so on any log that excites
the axis the two agree to many digits (tests/dynamics/servo/test_rls.py holds them together).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DELTA = 1e8  # P0 = DELTA * I: the prior's weight is 1 / DELTA


@dataclass(frozen=True)
class RlsResult:
    theta: np.ndarray  # (p,) the estimate after the last sample
    history: np.ndarray  # (N, p) the estimate after each sample


def rls(phi: np.ndarray, y: np.ndarray, lam: float = 1.0, delta: float = DELTA) -> RlsResult:
    """phi (N, p) regressors, y (N,) outputs; lam the forgetting factor (1: none)."""
    n, p = phi.shape
    theta = np.zeros(p)
    pm = np.eye(p) * delta
    hist = np.empty((n, p))
    for k in range(n):
        f = phi[k]
        pf = pm @ f
        g = pf / (lam + f @ pf)
        theta = theta + g * (y[k] - f @ theta)
        pm = (pm - np.outer(g, pf)) / lam
        pm = 0.5 * (pm + pm.T)  # keep P symmetric against rounding
        hist[k] = theta
    return RlsResult(theta, hist)
