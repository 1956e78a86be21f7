"""Batch least squares: the check on the recursive estimate, and the covariance the confidence
intervals come from.

The covariance is the heteroskedasticity- and autocorrelation-consistent (Newey-West, Bartlett
weights over HAC_LAGS lags) sandwich (F'F)^-1 S (F'F)^-1: the equation error of a model fitted on
count increments is not white (an encoder's quantisation error enters two neighbouring
increments; a real plant adds what the model leaves out), and the textbook sigma^2 (F'F)^-1 would
claim intervals narrower than the data support.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

HAC_LAGS = 8  # ticks of residual correlation that the covariance allows for


@dataclass(frozen=True)
class LsResult:
    theta: np.ndarray  # (p,)
    cov: np.ndarray  # (p, p) HAC covariance of theta
    residuals: np.ndarray  # (N,)
    condition: float  # condition number of the (column-scaled) regressor matrix


def batch_ls(phi: np.ndarray, y: np.ndarray, lags: int = HAC_LAGS) -> LsResult:
    scale = np.sqrt((phi ** 2).sum(axis=0))
    scale[scale == 0] = 1.0
    fs = phi / scale
    theta_s, *_ = np.linalg.lstsq(fs, y, rcond=None)
    sv = np.linalg.svd(fs, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    theta = theta_s / scale
    e = y - phi @ theta
    return LsResult(theta, hac_covariance(phi, e, lags), e, cond)


def hac_covariance(jac: np.ndarray, e: np.ndarray, lags: int = HAC_LAGS) -> np.ndarray:
    """The Newey-West covariance of a least squares estimate with Jacobian (regressors) jac and
    residuals e."""
    inv = np.linalg.pinv(jac.T @ jac)
    ue = jac * e[:, None]
    s = ue.T @ ue
    for lag in range(1, min(lags, len(e) - 1) + 1):
        g = ue[lag:].T @ ue[:-lag]
        s += (1.0 - lag / (lags + 1)) * (g + g.T)
    n, p = jac.shape
    return inv @ s @ inv * (n / max(n - p, 1))
