"""Accuracy against the truth (exact IK or held-out measurements), in the user's units."""

from __future__ import annotations

import numpy as np

from nnik.machine.scenario import Scenario


def error_stats(pred: np.ndarray, truth: np.ndarray) -> dict:
    """Absolute error per output: max, RMS and 99th percentile."""
    err = np.abs(np.asarray(pred, dtype=np.float64) - truth)
    return {
        "max_abs": err.max(0).tolist(),
        "rms": np.sqrt((err**2).mean(0)).tolist(),
        "p99": np.percentile(err, 99, axis=0).tolist(),
    }


def relative_pct(pred: np.ndarray, truth: np.ndarray) -> list[float]:
    """Seed 004-style relative error: mean |error| over the output's span, in percent."""
    span = truth.max(0) - truth.min(0)
    return (100 * np.abs(pred - truth).mean(0) / span).tolist()


def position_error_um(scn: Scenario, pred_units: np.ndarray, p_mm: np.ndarray) -> dict | None:
    """Where the commanded joints actually put the head: |FK(pred) - p| in um (analytic only)."""
    m = scn.mechanism
    if not m.analytic:
        return None
    p_hat = m.forward(m.q_rest + scn.actuator.from_units(pred_units))
    d = np.linalg.norm(p_hat - p_mm, axis=1) * 1000
    return {"max": float(d.max()), "rms": float(np.sqrt((d**2).mean())), "p99": float(np.percentile(d, 99))}
