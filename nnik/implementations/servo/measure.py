"""What tuning scores a simulated run by (all in um, from positions in counts):

- contour error: the distance from the carriage at tick k to the reference path (the polyline
  through the reference points' count middles), searched over the path's pieces within +-WINDOW_S
  of tick k. The window keeps a path that comes back near itself (a circle, a there-and-back) from
  matching its other pass; a carriage lagging more than the window is scored against the nearest
  piece inside it, which only overstates a very poor controller's error;
- overshoot: per axis, at every hold of that axis' reference (it stops after moving, a step's
  target included), the farthest the carriage goes past the hold point in the direction it arrived
  from; the worst over holds and axes;
- final error: the distance from the carriage to the reference at the last tick (a contour error
  alone does not see an axis that lags along the path and never arrives);
- saturation: the share of ticks at which either duty sits at +-duty_max.
"""

from __future__ import annotations

import numpy as np

WINDOW_S = 0.5
CHUNK = 1024


def _seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    l2 = (ab * ab).sum(axis=-1)
    t = np.clip(((p - a) * ab).sum(axis=-1) / np.where(l2 > 0, l2, 1.0), 0.0, 1.0)
    return np.hypot(*np.moveaxis(p - (a + ab * t[..., None]), -1, 0))


def contour_counts(pos: np.ndarray, ref_mid: np.ndarray, window: int) -> np.ndarray:
    """Distance (counts) of pos[k] to the polyline ref_mid over pieces k-window .. k+window."""
    n = len(ref_mid)
    if n == 1:
        return np.hypot(*(pos - ref_mid[0]).T)
    out = np.empty(len(pos))
    offs = np.arange(-window, window + 1)[None, :]
    for s in range(0, len(pos), CHUNK):  # bounded memory on long jobs
        k = np.arange(s, min(len(pos), s + CHUNK))[:, None]
        j = np.clip(offs + k, 0, n - 2)
        out[s:s + len(k)] = _seg_dist(pos[s:s + len(k), None, :], ref_mid[j], ref_mid[j + 1]).min(axis=1)
    return out


def overshoot_counts(pos: np.ndarray, ref: np.ndarray) -> float:
    """The worst overshoot past a hold point (counts), over both axes."""
    worst = 0.0
    for i in range(2):
        r = ref[:, i]
        v = np.diff(r)
        k = 0
        while k < len(v):
            if v[k] != 0 and (k + 1 >= len(v) or v[k + 1] == 0):
                arrive = np.sign(v[k])
                end = k + 1
                while end < len(v) and v[end] == 0:
                    end += 1
                hold = r[k + 1]
                past = (pos[k + 1:end + 1, i] - (hold + 0.5)) * arrive
                if past.size:
                    worst = max(worst, float(past.max()))
                k = end
            else:
                k += 1
    return worst


def score_run(cfg, ref_counts: np.ndarray, pos: np.ndarray, duty: np.ndarray) -> dict:
    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    um = cfg.um_per_count
    win = max(1, int(round(WINDOW_S / cfg.tick_s)))
    c = contour_counts(pos, ref + 0.5, win) * um
    return {"rms_contour_um": float(np.sqrt((c * c).mean())), "max_contour_um": float(c.max()),
            "overshoot_um": overshoot_counts(pos, ref) * um,
            "final_error_um": float(np.hypot(*(pos[-1] - ref[-1] - 0.5))) * um,
            "saturated_fraction": float((np.abs(duty) >= cfg.duty_max).any(axis=1).mean())}
