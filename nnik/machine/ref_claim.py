"""What a measured machine's implementation may claim: its max error against the machine over
the marks' hull, estimated by a parametric bootstrap of the reference model.

An implementation ``I`` compiled from the reference ``R`` errs against the machine ``T`` by
``I - T = d + e`` with ``d = I - R`` (known exactly on the dense check set) and ``e = R - T`` (not
known anywhere). The bootstrap draws ``e``'s distribution from the data and the noise model:

* replicate readings ``q*_b = R(marks) + n*_b``, ``n*_b`` drawn from the stated (or estimated)
  noise: uniform over the rounding step, Gaussian for position noise;
* the chosen reference refitted to them, same candidate and same hyperparameters (the RBF's
  smoothing, the GP's kernel), gives ``R*_b``; ``e*_b = R*_b - R`` on a regular grid over the
  marks' box is a draw of the reference's error field (its noise propagation and, through
  re-smoothing the smooth ``R``, its smoothing bias);
* an implementation's claim is the ``LEVEL`` quantile over the replicates of
  ``max over the check points |d + e*_b|``: the alignment of ``d``'s peaks with the reference's
  errors is what the bootstrap measures, neither the sum of the two maxima (which assumes they
  coincide) nor ``d`` alone (which assumes ``e`` vanishes there);
* the reference's own estimated error (the error floor) is the same with ``d = 0``.

A reference not refittable here (the MLP, trained once) borrows the refit of the best CV
candidate that is, the nearest model of the same marks; the method string says so.

This module is machine/data level: it never imports nnik.implementations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

BOOT = 40  # bootstrap replicates
LEVEL = 0.9  # the claim: this quantile of the replicates' max error (a one-sided 90 % bound)
BOOT_SEED = 15
GRID_MIN, GRID_MAX, GRID_PER_MARK = 65, 257, 6  # grid nodes per axis: GRID_PER_MARK x sqrt(marks), clipped


TOP_CELLS = 64  # grid cells (highest bound first) a replicate's claim is first evaluated in


def _ranges(starts: np.ndarray, lens: np.ndarray) -> np.ndarray:
    """The indices of the ranges [start, start + len), concatenated."""
    return np.arange(lens.sum()) - np.repeat(np.cumsum(lens) - lens, lens) + np.repeat(starts, lens)


@dataclass
class ErrorFields:
    """``BOOT`` draws of the reference's error field on a regular grid over the marks' box (mm)."""

    lo: np.ndarray  # (2,) mm
    hi: np.ndarray  # (2,) mm
    fields: np.ndarray  # (B, gy, gx, 2) float32: e*_b at the grid nodes
    inside: np.ndarray  # (gy, gx) bool: the node lies inside the marks' hull
    method: str

    def _cells(self, p_mm: np.ndarray):
        g = np.array(self.fields.shape[2:0:-1])  # (gx, gy)
        t = (np.asarray(p_mm, dtype=np.float64) - self.lo) / (self.hi - self.lo) * (g - 1)
        t = np.clip(t, 0.0, g - 1 - 1e-9)
        i0 = np.floor(t).astype(np.int64)
        return i0, t - i0

    def at(self, b: int, p_mm: np.ndarray, cells=None) -> np.ndarray:
        """(N, 2) replicate b's error field at p_mm, bilinear between grid nodes."""
        (i0, w) = cells if cells is not None else self._cells(p_mm)
        f = self.fields[b]
        ix, iy, wx, wy = i0[:, 0], i0[:, 1], w[:, :1], w[:, 1:]
        return ((1 - wy) * ((1 - wx) * f[iy, ix] + wx * f[iy, ix + 1])
                + wy * ((1 - wx) * f[iy + 1, ix] + wx * f[iy + 1, ix + 1]))

    @property
    def emax(self) -> float:
        return float(np.abs(self.fields).max())

    def claim(self, p_mm: np.ndarray, d: np.ndarray) -> float:
        """The LEVEL quantile over replicates of max |d + e*_b| over the points (worst output);
        ``d`` (N, 2) is the implementation's error against the reference there. Exact, with
        few points evaluated per replicate (10^6 check points: about a second)."""
        d = np.asarray(d, dtype=np.float64).reshape(-1, 2)
        a = np.abs(d)
        # only points within 2 emax of the largest |d| can hold a replicate's max
        keep = np.any(a >= a.max(0) - 2 * self.emax, axis=1)
        p, d = np.asarray(p_mm, dtype=np.float64).reshape(-1, 2)[keep], d[keep]
        cells = self._cells(p)
        # exact, but few points evaluated: within a grid cell a replicate's field is one bilinear
        # patch, bounded by its corners, so a cell's bound is d's extreme there plus the corners'.
        # Each replicate is evaluated where d peaks (either way, per output) in the TOP_CELLS cells
        # of highest bound, then at every point of the cells whose bound could still beat that
        gx = self.fields.shape[2]
        cell = cells[0][:, 1] * gx + cells[0][:, 0]
        order = np.argsort(cell, kind="stable")
        cs, ds, ps = cell[order], d[order], p[order]
        c0, c1 = cells[0][order], cells[1][order]
        new = np.r_[True, cs[1:] != cs[:-1]]
        seg = np.cumsum(new) - 1
        starts = np.flatnonzero(new)
        counts = np.diff(np.r_[starts, len(cs)])
        dmax, dmin = np.maximum.reduceat(ds, starts, axis=0), np.minimum.reduceat(ds, starts, axis=0)
        peak = np.flatnonzero(np.any((ds >= dmax[seg]) | (ds <= dmin[seg]), axis=1))
        peak_start = np.searchsorted(seg[peak], np.arange(len(starts)))
        peak_count = np.diff(np.r_[peak_start, len(peak)])
        cx, cy = cs[starts] % gx, cs[starts] // gx

        def worst(b, idx):
            return float(np.abs(ds[idx] + self.at(b, ps[idx], (c0[idx], c1[idx]))).max())
        m = []
        for b in range(len(self.fields)):
            f = self.fields[b]
            corners = np.stack([f[cy, cx], f[cy, cx + 1], f[cy + 1, cx], f[cy + 1, cx + 1]])
            bound = np.maximum(dmax + corners.max(0), -(dmin + corners.min(0))).max(1)
            top = np.argpartition(bound, len(bound) - TOP_CELLS)[-TOP_CELLS:] if len(bound) > TOP_CELLS else \
                np.arange(len(bound))
            low = worst(b, peak[_ranges(peak_start[top], peak_count[top])])
            cand = np.flatnonzero(bound > low)
            if len(cand):  # every point of those cells
                low = max(low, worst(b, _ranges(starts[cand], counts[cand])))
            m.append(low)
        return float(np.quantile(m, LEVEL))

    def floors(self) -> np.ndarray:
        """(2,) the reference's own estimated max error over the hull (d = 0), per output."""
        m = np.abs(self.fields[:, self.inside]).max(axis=1)  # (B, 2)
        return np.quantile(m, LEVEL, axis=0)

    def rms(self) -> np.ndarray:
        """(2,) RMS of the replicates' error fields inside the hull, per output."""
        return np.sqrt((self.fields[:, self.inside].astype(np.float64) ** 2).mean(axis=(0, 1)))


def draw_noise(rng: np.random.Generator, noise, n: int) -> np.ndarray:
    """(n, 2) readings' noise as the model says: uniform over the rounding step, plus Gaussian
    for the rest of its variance."""
    step = float(getattr(noise, "step", 0.0) or 0.0)
    out = rng.uniform(-step / 2, step / 2, (n, 2)) if step else np.zeros((n, 2))
    rest = np.maximum(np.asarray(noise.variance, dtype=np.float64) - step ** 2 / 12, 0.0)
    return out + rng.normal(0.0, 1.0, (n, 2)) * np.sqrt(rest)


def bootstrap_fields(refit: Callable, x_marks: np.ndarray, q_fit: np.ndarray, predict: Callable,
                     box: tuple[np.ndarray, np.ndarray], inside: Callable, noise, method: str) -> ErrorFields:
    """``refit(x, q) -> predictor (p_mm -> q)`` is the chosen candidate refitted to readings q at
    the marks' scaled inputs ``x_marks`` (q (n, 2, B): B replicates at once, predictions (m, 2, B)); ``q_fit`` the reference's values at the marks,
    ``predict(p_mm)`` the reference; ``box`` (lo, hi) mm the marks' box, ``inside(p_mm)`` the
    hull test."""
    n = len(x_marks)
    g = int(np.clip(GRID_PER_MARK * np.sqrt(n), GRID_MIN, GRID_MAX))
    lo, hi = (np.asarray(v, dtype=np.float64) for v in box)
    gx, gy = np.linspace(lo[0], hi[0], g), np.linspace(lo[1], hi[1], g)
    nodes = np.stack(np.meshgrid(gx, gy, indexing="xy"), -1).reshape(-1, 2)
    base = predict(nodes)
    rng = np.random.default_rng(BOOT_SEED)
    draws = np.stack([draw_noise(rng, noise, n) for _ in range(BOOT)], -1)  # (n, 2, BOOT)
    f = refit(x_marks, q_fit[:, :, None] + draws)  # every replicate at once: one factorisation
    fields = (f(nodes) - base[:, :, None]).transpose(2, 0, 1).reshape(BOOT, g, g, 2).astype(np.float32)
    return ErrorFields(lo, hi, fields, inside(nodes).reshape(g, g), method)


PAIR_MARKS = 1500  # marks whose pairs estimate the unresolved error's covariance (a fixed subset beyond)
LAGS = 12  # distance bins of that estimate, out to half the hull's diameter


def correlation_length(p_mm: np.ndarray, r: np.ndarray, var: np.ndarray, diameter: float) -> float:
    """The correlation length l (mm) of the CV residuals' spatially correlated part: the pairs'
    mean products r_i r_j, binned by distance (the noise, independent, drops out of every pair),
    least-squares fitted by var x exp(-h^2 / (2 l^2)) over candidate lengths, pooled over outputs."""
    if len(p_mm) > PAIR_MARKS:
        keep = np.random.default_rng(BOOT_SEED).choice(len(p_mm), PAIR_MARKS, replace=False)
        p_mm, r = p_mm[keep], r[keep]
    i, j = np.triu_indices(len(p_mm), 1)
    h = np.linalg.norm(p_mm[i] - p_mm[j], axis=1)
    prod = r[i] * r[j]  # (pairs, 2)
    edges = np.linspace(0.0, diameter / 2, LAGS + 1)
    k = np.digitize(h, edges) - 1
    ok = (k >= 0) & (k < LAGS)
    cnt = np.bincount(k[ok], minlength=LAGS).astype(np.float64)
    cov = np.stack([np.bincount(k[ok], prod[ok, o], minlength=LAGS) for o in range(2)], 1) / np.maximum(cnt, 1)[:, None]
    mid = (edges[:-1] + edges[1:]) / 2
    lengths = diameter * np.geomspace(1e-3, 1.0, 61)
    def loss(ell):
        model = var[None, :] * np.exp(-mid[:, None] ** 2 / (2 * ell ** 2))
        return float((cnt[:, None] * (cov - model) ** 2).sum())
    return float(min(lengths, key=loss))


ATOMS = 161  # the deconvolved distribution's support points
EM_STEPS = 400


def deconvolve(r: np.ndarray, step: float, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distribution of u in r = u + noise (noise: uniform over ``step`` plus Gaussian of std
    ``tau`` per mark): the nonparametric maximum likelihood estimate (Kiefer-Wolfowitz) on a grid
    of atoms over [-max|r|, max|r|], by EM. Returns (atoms, weights)."""
    from scipy.special import ndtr

    m = float(np.abs(r).max()) or 1e-12
    atoms = np.linspace(-m, m, ATOMS)
    z = r[:, None] - atoms[None, :]
    t = np.maximum(tau, 1e-3 * max(step, 1e-9))[:, None]
    if step:
        lik = (ndtr((z + step / 2) / t) - ndtr((z - step / 2) / t)) / step
    else:
        lik = np.exp(-0.5 * (z / t) ** 2) / t
    w = np.full(ATOMS, 1.0 / ATOMS)
    for _ in range(EM_STEPS):
        post = lik * w
        post /= np.maximum(post.sum(1, keepdims=True), 1e-300)
        w = post.mean(0)
    return atoms, w


def add_unresolved(ef: ErrorFields, p_marks: np.ndarray, cv_resid: np.ndarray, noise, diameter: float) -> np.ndarray:
    """The part of the reference's error its refit does not reproduce (the bias against a
    machine it does not model), from the CV residuals r: per output, the distribution of u in
    r = u + (bootstrap variance, Gaussian) + noise, deconvolved (nonparametric maximum
    likelihood), and the correlation length l the residuals' pairs show. Each replicate gets a
    field with that marginal distribution: a Gaussian random field of length l (white noise
    smoothed by a Gaussian of l / sqrt(2)) mapped through the distribution's quantiles
    (Gaussian anamorphosis), its tails cut at the 1 / (2 n) quantile the n marks resolve.
    Returns the added fields' variance (2,)."""
    from scipy.ndimage import gaussian_filter
    from scipy.special import ndtr

    n = len(p_marks)
    cells = ef._cells(p_marks)
    boot_sq = np.mean([ef.at(b, p_marks, cells) ** 2 for b in range(len(ef.fields))], axis=0)  # (n, 2)
    r = np.asarray(cv_resid, dtype=np.float64)
    step = float(getattr(noise, "step", 0.0) or 0.0)
    gauss = np.maximum(np.asarray(noise.variance) - step ** 2 / 12, 0.0)
    var = np.maximum((r ** 2).mean(0) - np.asarray(noise.variance) - boot_sq.mean(0), 0.0)
    if not np.any(var > 0):
        return var
    ell = correlation_length(p_marks, r, var, diameter)
    g = np.array(ef.fields.shape[2:0:-1])
    sig = ell / np.sqrt(2) / ((ef.hi - ef.lo) / (g - 1))  # grid units per axis (x, y)
    pad = int(np.ceil(3 * sig.max()))
    rng = np.random.default_rng(BOOT_SEED + 1)
    added = np.zeros(2)
    for o in range(2):
        if var[o] <= 0:
            continue
        atoms, w = deconvolve(r[:, o], step, np.sqrt(gauss[o] + boot_sq[:, o]))
        cdf = np.cumsum(w)
        for b in range(len(ef.fields)):
            f = gaussian_filter(rng.normal(size=(g[1] + 2 * pad, g[0] + 2 * pad)), sigma=(sig[1], sig[0]), mode="wrap")
            f = f[pad:pad + g[1], pad:pad + g[0]]
            pr = np.clip(ndtr(f / f.std()), 0.5 / n, 1 - 0.5 / n)
            u = atoms[np.minimum(np.searchsorted(cdf, pr), ATOMS - 1)]
            ef.fields[b, :, :, o] += u.astype(np.float32)
            added[o] += float((u ** 2).mean()) / len(ef.fields)
    ef.method += (f"; plus the error the refit does not reproduce (the CV residuals less noise and bootstrap "
                  f"variance, deconvolved; RMS {np.sqrt(added.max()):.3g}) as a field of the residuals' "
                  f"correlation length {ell:.3g} mm")
    return added
