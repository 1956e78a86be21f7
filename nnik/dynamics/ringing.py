"""The two figures a shaper trades (issue 18): ringing after stops and corners, and the tip's
contour error, from a base trajectory held over each stepper tick.

ringing: the peak tip deviation from the programmed path between 20 ms and 200 ms after each
stop or corner of the planned motion (a corner: the commanded direction turns by more than
CORNER_DEG within one sample).
"""

from __future__ import annotations

import numpy as np

from nnik.dynamics.axis import tip_xy

WINDOW_S = (0.020, 0.200)
CORNER_DEG = 30.0
TAIL_S = 0.3  # rest simulated after the job, so the last stop's ringing is seen


def tip_track(base_mm: np.ndarray, tick_hz: float, dyn: dict, tail_s: float = TAIL_S) -> np.ndarray:
    """The tip (T + tail, 2) of a base held over each tick (T, 2), the machine at rest at the
    start, with tail_s of rest after the end."""
    tail = int(round(tail_s * tick_hz))
    base = np.concatenate([base_mm, np.repeat(base_mm[-1:], tail, 0)]) if len(base_mm) else base_mm
    return tip_xy(base, 1.0 / tick_hz, dyn["f_hz"], dyn["zeta"])


def events(planned_mm: np.ndarray, sample_hz: float, corner_deg: float = CORNER_DEG) -> np.ndarray:
    """Times (s) of each stop (the planned motion comes to rest) and each corner (its direction
    turns by more than corner_deg between consecutive moving samples) of planned samples (N, 2)."""
    return event_index(planned_mm, corner_deg) / sample_hz


def event_index(planned_mm: np.ndarray, corner_deg: float = CORNER_DEG) -> np.ndarray:
    """events() as sample indices (the sample at which the motion has stopped or turned)."""
    if len(planned_mm) < 3:
        return np.zeros(0, np.int64)
    d = np.diff(planned_mm, axis=0)
    speed = np.hypot(d[:, 0], d[:, 1])
    moving = speed > 1e-9
    stops = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    if moving[-1]:
        stops = np.append(stops, len(d))
    idx = np.flatnonzero(moving)
    u = d[idx] / speed[idx, None]
    cosang = np.sum(u[1:] * u[:-1], axis=1)
    # a turn between adjacent moving samples (a start after a rest is not a corner)
    turn = np.flatnonzero((cosang < np.cos(np.radians(corner_deg))) & (np.diff(idx) == 1))
    corners = idx[turn + 1]
    return np.unique(np.concatenate([stops, corners])).astype(np.int64)


def ringing(dev_um: np.ndarray, tick_hz: float, at_s: np.ndarray, window_s=WINDOW_S) -> dict:
    """Peak of dev_um (per tick) within window_s after each event time, the window ending early
    where the next event begins (its own transient is not this one's ringing): the max over
    events, their mean and how many were seen."""
    peaks = []
    at_s = np.sort(np.asarray(at_s, float))
    for i, t in enumerate(at_s):
        end = min(t + window_s[1], at_s[i + 1]) if i + 1 < len(at_s) else t + window_s[1]
        lo, hi = int(round((t + window_s[0]) * tick_hz)), int(round(end * tick_hz))
        seg = dev_um[lo:min(hi, len(dev_um))]
        if len(seg):
            peaks.append(float(seg.max()))
    if not peaks:
        return {"max": 0.0, "mean": 0.0, "n": 0}
    return {"max": max(peaks), "mean": float(np.mean(peaks)), "n": len(peaks)}
