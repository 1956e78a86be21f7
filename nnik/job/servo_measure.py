"""A closed-loop job's figures, measured on the carriage's true position (after backlash, in um)
against the reference (nnik.job.reference.Reference.um, the middle of each reference count).

- contour error: the distance from the carriage at each tick to the reference PATH (the polyline
  through the per-tick reference points, a step's jump included), not to the tick's reference
  point: a carriage that lags along the path has no contour error, only tracking error;
- tracking error per axis: the carriage less the tick's reference point;
- per step (;@step): overshoot past the target along the step, settling time (the last time the
  carriage is outside +-2 % of the step, at least +-2 counts, of the target), steady-state error
  (the mean distance to the target over the hold's last 10 %);
- at reversals (a reference axis' velocity changes sign, a circle's quadrants): the largest
  contour error within REVERSAL_S of each;
- the duty's saturated share of the ticks.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

SETTLE_BAND = 0.02  # of the step
SETTLE_MIN_COUNTS = 2
REVERSAL_S = 0.25
DENSE_UM = 20.0  # the path's vertices are at most this far apart for the search (exact distances after)


def _dense(path: np.ndarray) -> np.ndarray:
    """The polyline with long segments (a step's jump) split so no piece exceeds DENSE_UM."""
    d = np.hypot(*np.diff(path, axis=0).T)
    k = np.maximum(1, np.ceil(d / DENSE_UM).astype(np.int64))
    if (k == 1).all():
        return path
    parts = [path[:1]]
    t = np.concatenate([np.arange(1, n + 1) / n for n in k])
    seg = np.repeat(np.arange(len(k)), k)
    pts = path[seg] + (path[seg + 1] - path[seg]) * t[:, None]
    parts.append(pts)
    return np.concatenate(parts)


def _seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    L2 = (ab * ab).sum(axis=1)
    t = np.clip(((p - a) * ab).sum(axis=1) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
    q = a + ab * t[:, None]
    return np.hypot(*(p - q).T)


def path_distance(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Exact distance from each point (M, 2) to the polyline path (N, 2): the nearest vertex d0
    bounds it; every segment with an end within d0 + (longest piece) / 2 is a candidate."""
    path = np.asarray(path, dtype=float)
    keep = np.concatenate([[True], np.any(np.diff(path, axis=0) != 0, axis=1)])  # a hold is one vertex
    path = _dense(path[keep]) if keep.sum() > 1 else path[:1]
    points = np.asarray(points, dtype=float)
    if len(path) == 1:
        return np.hypot(*(points - path[0]).T)
    tree = cKDTree(path)
    d0, _ = tree.query(points)
    half = float(np.hypot(*np.diff(path, axis=0).T).max()) / 2
    out = d0.copy()
    near = tree.query_ball_point(points, d0 + half + 1e-9)
    idx = np.repeat(np.arange(len(points)), [len(n) for n in near])
    v = np.concatenate([np.asarray(n, dtype=np.int64) for n in near])
    for s in (v - 1, v):  # the segments before and after each candidate vertex
        ok = (s >= 0) & (s < len(path) - 1)
        d = _seg_dist(points[idx[ok]], path[s[ok]], path[s[ok] + 1])
        np.minimum.at(out, idx[ok], d)
    return out


def _stats(e: np.ndarray) -> dict:
    e = np.abs(e)
    return {"max_um": float(e.max()) if len(e) else 0.0, "rms_um": float(np.sqrt((e * e).mean())) if len(e) else 0.0}


def steps(ref_um: np.ndarray, table_um: np.ndarray, step_ticks, tick_s: float, um_per_count: float) -> list[dict]:
    out = []
    bounds = list(step_ticks) + [len(ref_um)]
    for k0, k1 in zip(step_ticks, bounds[1:]):
        moved = np.flatnonzero(np.any(ref_um[k0:k1] != ref_um[k0], axis=1))
        end = k0 + (moved[0] if len(moved) else k1 - k0)  # the hold: until the reference moves again
        a, b = ref_um[k0 - 1], ref_um[k0]
        step = b - a
        size = float(np.hypot(*step))
        if size == 0 or end - k0 < 2:
            continue
        u = step / size
        pos = table_um[k0:end]
        along = (pos - b) @ u
        dist = np.hypot(*(pos - b).T)
        band = max(SETTLE_BAND * size, SETTLE_MIN_COUNTS * um_per_count)
        outside = np.flatnonzero(dist > band)
        tail = dist[len(dist) - max(1, len(dist) // 10):]
        mm = lambda p: ((p - um_per_count / 2) / 1000).round(4).tolist()  # noqa: E731 (the count, not its middle)
        out.append({"tick": int(k0), "from_mm": mm(a), "to_mm": mm(b),
                    "size_mm": size / 1000, "overshoot_um": float(max(0.0, along.max())),
                    "settling_s": None if len(outside) and outside[-1] == len(dist) - 1
                    else float((outside[-1] + 1 if len(outside) else 0) * tick_s),
                    "settle_band_um": band, "steady_state_um": float(tail.mean()), "hold_s": (end - k0) * tick_s})
    return out


def reversals(ref_um: np.ndarray, contour: np.ndarray, step_ticks, tick_s: float) -> dict:
    """The contour error near each sign change of an axis' reference velocity (not at steps: a
    jump is no reversal of a path)."""
    v = np.diff(ref_um, axis=0)
    v[[k - 1 for k in step_ticks if k > 0]] = 0  # a step's jump
    ticks = []
    for a in range(2):
        nz = np.flatnonzero(v[:, a] != 0)
        s = np.sign(v[nz, a])
        flips = nz[1:][s[1:] != s[:-1]]
        ticks += flips.tolist()
    w = max(1, int(round(REVERSAL_S / tick_s)))
    worst = [float(contour[max(0, k - w):k + w + 1].max()) for k in sorted(ticks)]
    return {"count": len(worst), "window_s": REVERSAL_S, "max_um": max(worst) if worst else None,
            "mean_um": float(np.mean(worst)) if worst else None}


def measure(ref, trace) -> dict:
    """The job's figures from its Reference and a closed-loop trace (ref, counts, duty, table_um)."""
    ref_um, table = ref.um, np.asarray(trace.table_um, dtype=float)
    contour = path_distance(table, ref_um)
    track = table - ref_um
    return {
        "ticks": len(ref_um), "seconds": len(ref_um) * ref.tick_s,
        "contour_um": _stats(contour),
        "tracking_um": {"x": _stats(track[:, 0]), "y": _stats(track[:, 1])},
        "saturated_fraction": float(trace.saturated_fraction),
        "steps": steps(ref_um, table, ref.step_ticks, ref.tick_s, ref.um_per_count),
        "reversals": reversals(ref_um, contour, ref.step_ticks, ref.tick_s),
        "final_error_um": float(np.hypot(*track[-1])),
    }, contour
