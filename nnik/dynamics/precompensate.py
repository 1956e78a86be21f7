"""Seed 003's problem, solved by model inversion: the base trajectory that makes the modelled tip
follow a reference, so a job can be rewritten offline (`nnik job --precompensate`).

Why inversion and not the seed's iterative optimisation: the base-excited model is linear and
minimum phase, so its inverse is exact and closed-form,
    base = r + LPF_tau[r'' / wn^2],  tau = 2 zeta / wn
(from wn^2 (b - x) + 2 zeta wn (b' - x') = x''), computed in one pass in milliseconds, where the
seed's fmincon took up to 93 s.  A trapezoid has steps in acceleration, which the inverse turns
into steps of a / wn^2 in the command (Klipper's reviewers rejected that), so the reference is
first made snap-limited: the planned motion through two moving averages of smooth_s each (each
one raises the order of continuity by one: a trapezoid's jerk and snap become finite).  The
averages round corners a little; that is part of the contour error reported for the method.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from nnik.dynamics.axis import wn


def smooth(p: np.ndarray, fs: float, smooth_s: float) -> np.ndarray:
    """p (N, 2) sampled at fs, at rest before and after, through two centred moving averages of
    about smooth_s each.  The result has w + 1 more samples of rest at each end (w = smooth_s fs),
    so it starts and ends at rest exactly where p does: sample k of p is sample k + w + 1 here."""
    w = max(1, int(round(smooth_s * fs)))
    q = np.concatenate([np.repeat(p[:1], 2 * w, 0), p, np.repeat(p[-1:], 2 * w, 0)]).astype(float)
    k = np.ones(w) / w
    for _ in range(2):  # "valid": each pass only averages samples that exist (w - 1 fewer)
        q = np.stack([np.convolve(q[:, i], k, mode="valid") for i in range(q.shape[1])], 1)
    return q


def invert(r: np.ndarray, fs: float, f_hz: tuple[float, float], zeta: tuple[float, float]) -> np.ndarray:
    """The base that makes the tip follow r (N, 2), sampled at fs, axis by axis."""
    dt = 1.0 / fs
    out = np.array(r, dtype=float)
    for i in range(r.shape[1]):
        x = np.asarray(r[:, i], float)
        acc = np.zeros_like(x)
        acc[1:-1] = (x[2:] - 2 * x[1:-1] + x[:-2]) / dt**2
        w = wn(f_hz[i])
        u = acc / w**2
        tau = 2.0 * zeta[i] / w
        if tau > 0:  # first-order low-pass, exact for a held input: y[k] = a y[k-1] + (1 - a) u[k]
            a = math.exp(-dt / tau)
            u = lfilter([1 - a], [1, -a], u)
        out[:, i] = x + u
    return out


def precompensated(planned: np.ndarray, fs: float, f_hz, zeta, smooth_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(reference, base): the planned samples (N, 2) smoothed (smooth() adds rest at both ends),
    and the base that makes the modelled tip follow that reference, with rest appended for the
    low-pass to settle (five of its time constants)."""
    tau = max(2.0 * z / wn(f) for f, z in zip(f_hz, zeta))
    tail = int(math.ceil(5 * tau * fs)) + 1
    ref = smooth(planned, fs, smooth_s)
    ref = np.concatenate([ref, np.repeat(ref[-1:], tail, 0)])
    return ref, invert(ref, fs, f_hz, zeta)


def gcode(base_mm: np.ndarray, fs: float, every: int, origin_mm: np.ndarray, header: list[str],
          tool: list[str] | None = None) -> tuple[list[str], list[int]]:
    """(lines, src): G1 lines through every every-th base sample (program mm, 4 decimals: 0.1 um),
    each with the feed that takes it there in every / fs seconds, and for each line the sample
    index it goes to (-1: not a move).  tool[k], when given, is a line to insert before the move
    to sample k (a tool change); repeated points are dropped."""
    n = len(base_mm)
    keep = list(range(0, n, every))
    if n and keep[-1] != n - 1:
        keep.append(n - 1)
    if tool:
        keep = sorted(set(keep) | {k for k, t in enumerate(tool) if t})
    prog = base_mm - origin_mm
    lines, src = list(header) + ["G21", "G90", f"G0 X{prog[0, 0]:.4f} Y{prog[0, 1]:.4f}"], [-1] * (len(header) + 2) + [0]
    last, last_k = prog[0], 0
    for k in keep[1:]:
        if tool and tool[k]:
            lines.append(tool[k])
            src.append(-1)
        p = prog[k]
        d = float(np.hypot(*(p - last)))
        if d < 1e-4:
            continue
        dt_min = (k - last_k) / fs / 60.0
        lines.append(f"G1 X{p[0]:.4f} Y{p[1]:.4f} F{max(d / dt_min, 1.0):.1f}")
        src.append(k)
        last, last_k = p, k
    lines.append("M400")
    src.append(-1)
    return lines, src


def least_squares(target: np.ndarray, fine_dt: float, dt: float, f_hz, zeta, smooth: float = 1e-2) -> np.ndarray:
    """The base on a grid of step dt (a whole number of fine_dt), linearly interpolated in
    between (as a controller that updates every dt), whose modelled tip best follows target
    (N, 2) sampled every fine_dt, in least squares, with a small penalty on the base's second
    differences (smooth x their squares, mm^2).  The tip is linear in the grid's values, so
    this is one linear solve per axis: the seed's optimisation without iterations.  The model is
    time-invariant, so every interior hat's response is one response shifted."""
    from scipy.linalg import lstsq
    from threadpoolctl import threadpool_limits

    from nnik.dynamics.axis import tip as tip_of

    k = int(round(dt / fine_dt))
    if k < 1 or abs(k * fine_dt - dt) > 1e-9 * dt:
        raise ValueError(f"the grid step {dt} s must be a whole number of {fine_dt} s")
    n_fine = len(target)
    m = (n_fine - 1) // k + 2
    t_fine = np.arange(n_fine) * fine_dt
    grid = np.arange(m) * dt
    out = np.zeros((m, target.shape[1]))
    for i in range(target.shape[1]):
        first = tip_of(np.interp(t_fine, grid, np.eye(1, m, 0)[0]), fine_dt, f_hz[i], zeta[i])
        hat = np.interp(t_fine, grid[:3], [0.0, 1.0, 0.0], right=0.0)  # the hat at grid[1]
        resp = tip_of(hat, fine_dt, f_hz[i], zeta[i])  # from rest at 0
        cols = np.zeros((n_fine, m))
        cols[:, 0] = first
        for j in range(1, m):
            sh = (j - 1) * k
            if sh < n_fine:
                cols[sh:, j] = resp[:n_fine - sh]
        d2 = np.diff(np.eye(m), 2, axis=0) * math.sqrt(smooth)
        a_ = np.vstack([cols, d2])
        b_ = np.concatenate([target[:, i], np.zeros(len(d2))])
        with threadpool_limits(1):  # one small solve: threads only contend (12x slower on 2 busy cores)
            out[:, i] = lstsq(a_, b_, lapack_driver="gelsy")[0]
    return out
