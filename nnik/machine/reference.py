"""A measured machine's reference model: a smooth map from position to actuator units, fitted to
the marks (the calibration CSV's rows) and chosen by k-fold cross-validation among candidates.

Candidates (each fitted to the residual of the marks' least-squares affine map, inputs scaled to
the marks' bounding box):

* ``poly<d>``: a least-squares polynomial of total degree d (1 = the affine map itself);
* ``rbf``: a thin-plate spline (scipy ``RBFInterpolator``), its smoothing chosen by the same CV;
* ``gp``: a Gaussian process (scikit-learn, Matern 5/2 kernel), with the known noise variance as
  ``alpha`` or, when the noise is not known, a fitted ``WhiteKernel``;
* ``mlp`` (passed in by the caller): the scenario's trained MLP, scored on its held-out rows
  instead of by CV (it trains for seconds per fit).

Noise, in output units per output, in this order of preference: what the scenario states
(``[mechanism] reading_step``: readings rounded to this step, uniform, variance step^2/12;
``[mechanism] noise_um``: position noise, 1 sigma per axis, carried through the affine map's
Jacobian), then the spread of repeated marks, then the Gaussian process's fitted white noise.

Error of the chosen reference against the machine, net of the noise:

* RMS: the CV residual r at a mark is (reference error there) + (noise), the two independent, so
  ``sqrt(max(mean r^2 + MS_MARGIN x its standard error - noise variance, RMS_FLOOR^2 x mean r^2))``;
* max (the error floor) and every implementation's claim: a parametric bootstrap of the chosen
  candidate under the noise model (nnik.machine.ref_claim): the LEVEL quantile of the replicates'
  max error over the marks' hull.

This module is machine/data level: it never imports nnik.implementations.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nnik.machine.ref_claim import BOOT, LEVEL, ErrorFields, add_unresolved, bootstrap_fields

FOLDS = 10  # k of the k-fold CV; leave-one-out up to LOO_MARKS marks (a fold then leaves the fewest gaps)
LOO_MARKS = 100
CV_SEED = 0
POLY_DEGREES = (1, 2, 3, 4)
RBF_SMOOTHING = (0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0)
GP_HYPER_MARKS = 500  # the marks the GP's hyperparameters are fitted to (a fixed subset beyond)
GP_MAX_MARKS = 1500  # a GP fit is O(n^3): beyond this it is left out (and the report says so)
RBF_MAX_MARKS = 4000  # beyond this the spline is local (64 nearest marks)
MS_MARGIN = 1.0  # standard errors of the CV mean square added before the noise is taken off (an upper estimate)
RMS_FLOOR = 0.2  # the estimated RMS is at least this fraction of the CV RMS (the noise is never known exactly)
CHUNK = 100_000


@dataclass
class Noise:
    variance: np.ndarray  # (2,) output units^2
    bound: np.ndarray  # (2,) the noise's practical bound (step/2 for rounding, 3 sigma otherwise)
    source: str
    step: float = 0.0  # the readings' rounding step: that part of the variance is uniform, the rest Gaussian

    def to_dict(self) -> dict:
        return {"variance": self.variance.tolist(), "std": np.sqrt(self.variance).tolist(), "bound": self.bound.tolist(),
                "source": self.source}


@dataclass
class Hull:
    """The marks' convex hull (mm)."""

    points: np.ndarray  # (k, 2) vertices
    equations: np.ndarray  # (f, 3): inside where a*x + b*y + c <= 0

    def inside(self, p_mm: np.ndarray, tol_mm: float = 1e-9) -> np.ndarray:
        p = np.asarray(p_mm, dtype=np.float64).reshape(-1, 2)
        return np.all(p @ self.equations[:, :2].T + self.equations[:, 2] <= tol_mm, axis=1)

    @property
    def area(self) -> float:
        x, y = self.points[:, 0], self.points[:, 1]
        return float(0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))

    def to_dict(self) -> dict:
        lo, hi = self.points.min(0), self.points.max(0)
        return {"x_mm": [float(lo[0]), float(hi[0])], "y_mm": [float(lo[1]), float(hi[1])], "area_mm2": self.area,
                "vertices": len(self.points)}


def convex_hull(p_mm: np.ndarray) -> Hull:
    from scipy.spatial import ConvexHull

    h = ConvexHull(p_mm)
    return Hull(p_mm[h.vertices], h.equations)


# ---- candidates -------------------------------------------------------------------------------
class _Scaled:
    """Inputs scaled to [-1, 1] over the marks' box; the candidate fits the affine residual."""

    def __init__(self, lo, hi):
        self.c, self.h = (lo + hi) / 2, np.maximum((hi - lo) / 2, 1e-12)

    def x(self, p_mm):
        return (np.asarray(p_mm, dtype=np.float64) - self.c) / self.h


def _poly_features(x: np.ndarray, degree: int) -> np.ndarray:
    return np.stack([x[:, 0] ** i * x[:, 1] ** (d - i) for d in range(degree + 1) for i in range(d + 1)], 1)


def _columns(y: np.ndarray) -> np.ndarray:
    """Readings (n, 2) or, for many replicates at once, (n, 2, B) as columns (n, 2 B)."""
    return y.reshape(len(y), -1)


def _fit_poly(degree: int):
    def fit(x, y):
        coef, *_ = np.linalg.lstsq(_poly_features(x, degree), _columns(y), rcond=None)
        return lambda xq: (_poly_features(xq, degree) @ coef).reshape(len(xq), *y.shape[1:])
    return fit


def _fit_rbf(smoothing: float, neighbors: int | None = None):
    def fit(x, y):
        from scipy.interpolate import RBFInterpolator

        f = RBFInterpolator(x, _columns(y), kernel="thin_plate_spline", smoothing=smoothing, degree=1,
                            neighbors=neighbors)
        return lambda xq: f(xq).reshape(len(xq), *y.shape[1:])
    return fit


def _gp_kernel(noise_var: float | None):
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    kern = ConstantKernel(1.0, (1e-6, 1e6)) * Matern(0.5, (1e-2, 1e2), nu=2.5)
    return kern + WhiteKernel(0.1, (1e-8, 1e3)) if noise_var is None else kern


def _gp(kernel, noise_var: float | None, x, y, optimize: bool):
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor

    alpha = 1e-8 if noise_var is None else max(float(noise_var), 1e-8)
    gp = GaussianProcessRegressor(kernel, alpha=alpha, optimizer="fmin_l_bfgs_b" if optimize else None, random_state=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return gp.fit(x, y)


def gp_kernels(x, y, noise_var: np.ndarray | None) -> list:
    """Per output, the GP's kernel with its hyperparameters fitted (marginal likelihood) to the marks,
    at most GP_HYPER_MARKS of them (a fixed subset beyond: each step of the fit is O(n^3), and a
    few hundred marks pin a length scale and an amplitude down); the CV folds reuse them
    (refitting them per fold costs seconds and moves the score little)."""
    if len(x) > GP_HYPER_MARKS:
        keep = np.sort(np.random.default_rng(CV_SEED).choice(len(x), GP_HYPER_MARKS, replace=False))
        x, y = x[keep], y[keep]
    return [_gp(_gp_kernel(None if noise_var is None else noise_var[o]), None if noise_var is None else noise_var[o],
                x, y[:, o], True).kernel_ for o in range(y.shape[1])]


GP_PREDICT_ENTRIES = 4_000_000  # kernel entries (query rows x marks) per chunk of a GP's prediction


def _gp_predict(gp, xq: np.ndarray) -> np.ndarray:
    """The GP's mean at xq, in chunks: its cross-kernel matrix grows with the marks."""
    rows = max(256, GP_PREDICT_ENTRIES // len(gp.X_train_))
    return np.concatenate([gp.predict(xq[i:i + rows]) for i in range(0, len(xq), rows)]) if len(xq) else gp.predict(xq)


def _fit_gp(kernels: list, noise_var: np.ndarray | None):
    """One GP per output with fixed kernels; alpha = the known noise variance, else the kernels'
    WhiteKernel. Readings (n, 2, B) fit B replicates at once (one factorisation per output)."""
    def fit(x, y):
        gps = [_gp(k, None if noise_var is None else noise_var[o], x, y[:, o], False) for o, k in enumerate(kernels)]
        return lambda xq: np.stack([_gp_predict(g, xq) for g in gps], 1)
    return fit


# ---- the reference ----------------------------------------------------------------------------
@dataclass
class Reference:
    """The chosen model, refitted to every mark, and what the CV says about it."""

    name: str
    n_marks: int
    predict_residual: Callable  # scaled x -> residual of the affine map
    scale: _Scaled
    affine: np.ndarray  # (3, 2): [1, x, y] -> q, in scaled x
    noise: Noise
    hull: Hull
    scores: dict  # candidate -> {"cv_rms": [2], "detail": str} or {"skipped": reason}
    est_rms: np.ndarray  # (2,) vs the machine, net of noise
    est_max: np.ndarray  # (2,)
    cv_rms: np.ndarray  # (2,) of the chosen candidate
    cv_max: np.ndarray
    detail: str = ""
    extra: dict = field(default_factory=dict)
    fields: ErrorFields | None = None  # the bootstrap's draws of the error field (nnik.machine.ref_claim)

    def claim(self, p_mm: np.ndarray, d: np.ndarray) -> float:
        """The max error against the machine an implementation claims at positions p_mm where it
        errs by d (N, 2) against this reference (see nnik.machine.ref_claim)."""
        return self.fields.claim(p_mm, d)

    def __call__(self, p_mm: np.ndarray) -> np.ndarray:
        p = np.asarray(p_mm, dtype=np.float64).reshape(-1, 2)
        out = np.empty((len(p), 2))
        for i in range(0, len(p), CHUNK):
            x = self.scale.x(p[i:i + CHUNK])
            out[i:i + CHUNK] = _poly_features(x, 1) @ self.affine + self.predict_residual(x)
        return out

    @property
    def error_max(self) -> float:
        """Estimated max |reference - machine| over the hull, worst output."""
        return float(self.est_max.max())

    @property
    def noise_floor(self) -> float:
        """The noise's 1 sigma, worst output: no model can be judged better than this on a single mark."""
        return float(np.sqrt(self.noise.variance.max()))

    def describe(self, unit: str = "") -> str:
        """What accuracy figures are measured against, for headers and the report."""
        u = f" {unit}" if unit else ""
        return (f"the reference model ({self.name}) fitted to {self.n_marks} marks (est. error {self.error_max:.3g}{u} "
                f"vs the machine, noise floor {self.noise_floor:.3g}{u})")

    def to_dict(self) -> dict:
        return {"chosen": self.name, "detail": self.detail, "marks": self.n_marks, "folds": folds_for(self.n_marks),
                "candidates": self.scores, "noise": self.noise.to_dict(),
                "cv_rms": self.cv_rms.tolist(), "cv_max_abs": self.cv_max.tolist(),
                "est_rms": self.est_rms.tolist(), "est_max": self.est_max.tolist(), "error_max": self.error_max,
                "noise_floor": self.noise_floor, "hull": self.hull.to_dict(), "claim_level": LEVEL,
                "method": (f"{folds_for(self.n_marks)}-fold CV among the candidates; est. RMS = sqrt(CV mean square "
                           f"+ {MS_MARGIN:g} standard error - noise variance), "
                           f"at least {RMS_FLOOR:g} x CV RMS; est. max = the {LEVEL:g} quantile of the max "
                           f"over the marks' hull of the reference's error in a parametric bootstrap "
                           f"({self.fields.method if self.fields is not None else '-'}) under the noise model"), **self.extra}


def known_noise(q: np.ndarray, jac: np.ndarray, reading_step: float = 0.0, noise_um: float = 0.0) -> Noise | None:
    """The noise the scenario states, in output units: rounding of the readings (uniform,
    step^2/12) plus position noise (1 sigma per axis, through the Jacobian jac (2 out, 2 in) in
    units per um). None if it states none."""
    if not reading_step and not noise_um:
        return None
    var = np.full(2, reading_step ** 2 / 12.0)
    pos_var = (noise_um ** 2) * (jac ** 2).sum(1)
    var = var + pos_var
    bound = reading_step / 2 + 3 * np.sqrt(pos_var)
    parts = ([f"readings rounded to {reading_step:g} (uniform, variance {reading_step ** 2 / 12:.4g})"] if reading_step
             else []) + ([f"position noise {noise_um:g} um (1 sigma)"] if noise_um else [])
    return Noise(var, bound, "stated: " + " + ".join(parts), float(reading_step))


def repeated_noise(p_mm: np.ndarray, q: np.ndarray) -> Noise | None:
    """The spread of readings taken at the same position (at least 10 repeats in all)."""
    _, inv, counts = np.unique(p_mm, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    if (counts - 1).sum() < 10:
        return None
    means = np.stack([np.bincount(inv, q[:, o]) / counts for o in range(2)], 1)
    dev = q - means[inv]
    var = (dev ** 2).sum(0) / (counts - 1).sum()
    return Noise(var, 3 * np.sqrt(var), f"estimated from {int((counts > 1).sum())} repeated marks")


def folds_for(n: int) -> int:
    return n if n <= LOO_MARKS else FOLDS


def _folds(n: int) -> np.ndarray:
    return np.random.default_rng(CV_SEED).permutation(n) % folds_for(n)


def _cv(fit, x, y, folds) -> np.ndarray:
    """Held-out residuals (n, 2) of `fit` over the folds (the affine map refitted per fold)."""
    res = np.empty_like(y)
    for k in range(int(folds.max()) + 1):
        tr, te = folds != k, folds == k
        a, *_ = np.linalg.lstsq(_poly_features(x[tr], 1), y[tr], rcond=None)
        f = fit(x[tr], y[tr] - _poly_features(x[tr], 1) @ a)
        res[te] = _poly_features(x[te], 1) @ a + f(x[te]) - y[te]
    return res


def _rms(r):
    return np.sqrt((r ** 2).mean(0))


def fit_reference(p_mm: np.ndarray, q: np.ndarray, noise: Noise | None = None,
                  extra: dict | None = None, gp: bool = True) -> Reference:
    """Fit every candidate by FOLDS-fold CV, pick the lowest CV mean square (both outputs), refit
    it to every mark. ``extra``: name -> (predict p_mm -> q, held-out positions (m, 2) mm, their
    residuals (m, 2)) for candidates scored elsewhere (the MLP): each residual stays paired with
    its own mark, whichever candidate wins."""
    p_mm = np.asarray(p_mm, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    n = len(p_mm)
    scale = _Scaled(p_mm.min(0), p_mm.max(0))
    x = scale.x(p_mm)
    folds = _folds(n)
    if noise is None:
        noise = repeated_noise(p_mm, q)
    use_gp = gp and n <= GP_MAX_MARKS
    known = None if noise is None else noise.variance
    if use_gp or (gp and noise is None):  # the kernels' fit is bounded (GP_HYPER_MARKS): it estimates the noise at any size
        a0, *_ = np.linalg.lstsq(_poly_features(x, 1), q, rcond=None)
        kernels = gp_kernels(x, q - _poly_features(x, 1) @ a0, known)
    if noise is None and gp:
        white = np.array([float(k.k2.noise_level) for k in kernels])
        noise = Noise(white, 3 * np.sqrt(white), f"estimated: the Gaussian process's fitted white noise "
                                                 f"({min(n, GP_HYPER_MARKS)} marks)")
    elif noise is None:
        noise = Noise(np.zeros(2), np.zeros(2), "unknown (the GP's estimate not asked): taken as 0")
    fits: dict[str, Callable] = {}
    scores: dict[str, dict] = {}
    resid: dict[str, np.ndarray] = {}
    for d in POLY_DEGREES:
        nt = (d + 1) * (d + 2) // 2
        if nt * 3 > n * (1 - 1 / folds_for(n)):
            scores[f"poly{d}"] = {"skipped": f"{nt} terms need at least {3 * nt} marks per fold"}
            continue
        fits[f"poly{d}"] = _fit_poly(d)
    neighbors = None if n <= RBF_MAX_MARKS else 64
    best_s = None
    for s in RBF_SMOOTHING:
        r = _cv(_fit_rbf(s, neighbors), x, q, folds)
        if best_s is None or (r ** 2).mean() < (resid["rbf"] ** 2).mean():
            best_s, resid["rbf"] = s, r
    fits["rbf"] = _fit_rbf(best_s, neighbors)
    if use_gp:
        fits["gp"] = _fit_gp(kernels, known)
    else:
        scores["gp"] = {"skipped": f"{n} marks (the GP is fitted up to {GP_MAX_MARKS})" if gp else "not asked"}
    for name, fit in fits.items():
        if name not in resid:
            resid[name] = _cv(fit, x, q, folds)
        scores[name] = {"cv_rms": _rms(resid[name]).tolist(), "cv_max_abs": np.abs(resid[name]).max(0).tolist()}
    scores["rbf"]["smoothing"] = best_s
    where = {name: p_mm for name in resid}  # the marks each candidate's held-out residuals belong to
    for name, (_, p_held, r) in (extra or {}).items():
        resid[name] = np.asarray(r, dtype=np.float64).reshape(-1, 2)
        where[name] = np.asarray(p_held, dtype=np.float64).reshape(-1, 2)
        if len(where[name]) != len(resid[name]):
            raise ValueError(f"{name}: {len(resid[name])} residuals for {len(where[name])} positions")
        scores[name] = {"cv_rms": _rms(resid[name]).tolist(), "cv_max_abs": np.abs(resid[name]).max(0).tolist(),
                        "scored_on": f"{len(resid[name])} held-out rows (not CV: trained once)"}
    chosen = min(resid, key=lambda k: float((resid[k] ** 2).mean()))
    r = resid[chosen]
    a, *_ = np.linalg.lstsq(_poly_features(x, 1), q, rcond=None)
    if chosen in fits:
        pr = fits[chosen](x, q - _poly_features(x, 1) @ a)
    else:  # an outside model: its prediction less the affine map
        ext = extra[chosen][0]
        pr = lambda xq: ext(xq * scale.h + scale.c) - _poly_features(xq, 1) @ a  # noqa: E731
    ms = (r ** 2).mean(0)
    se = (r ** 2).std(0) / np.sqrt(len(r))  # standard error of the CV mean square: few marks, wide margin
    est_rms = np.sqrt(np.maximum(ms - noise.variance + MS_MARGIN * se, RMS_FLOOR ** 2 * ms))
    detail = f"smoothing {best_s:g}" if chosen == "rbf" else ""
    hull = convex_hull(p_mm)
    ref = Reference(chosen, n, pr, scale, a, noise, hull, scores, est_rms, np.zeros(2), _rms(r), np.abs(r).max(0), detail)
    # the error field's bootstrap: the chosen candidate refitted to replicate readings (an outside
    # model borrows the best refittable candidate's refit)
    boot = chosen if chosen in fits else min(fits, key=lambda k: float((resid[k] ** 2).mean()))
    ref.fields = bootstrap_fields(_refit(fits[boot], scale), x, ref(p_mm), ref, (p_mm.min(0), p_mm.max(0)),
                                  lambda pq: hull.inside(pq, 1e-6), noise,
                                  f"{BOOT} replicates of {boot}" + ("" if boot == chosen else f" (for {chosen})"))
    add_unresolved(ref.fields, where[chosen], r, noise, float(np.linalg.norm(np.ptp(hull.points, 0))))
    ref.est_max = ref.fields.floors()
    return ref


def _refit(fit: Callable, scale: "_Scaled") -> Callable:
    """fit (a candidate's residual fit) -> refit(x, q): the affine map and the candidate refitted
    to readings q (n, 2), or B replicates of them at once (n, 2, B), at scaled inputs x, as a
    predictor of positions in mm. Every candidate is linear in the readings with its
    hyperparameters fixed, so the replicates share one factorisation."""
    def refit(x, q):
        a, *_ = np.linalg.lstsq(_poly_features(x, 1), _columns(q), rcond=None)
        f = fit(x, q - (_poly_features(x, 1) @ a).reshape(q.shape))

        def predict(p_mm):
            xq = scale.x(p_mm)
            return (_poly_features(xq, 1) @ a).reshape(len(xq), *q.shape[1:]) + f(xq)
        return predict
    return refit


HULL_WARN = 0.99  # warn when the marks' hull covers less than this fraction of [workspace]
_CACHE: dict = {}  # (scenario fingerprint, MLP residuals' hash) -> Reference: every stage rebuilds the Problem


def scenario_noise(scn) -> Noise | None:
    """The noise a measured scenario states ([mechanism] reading_step, noise_um), with the
    marks' affine Jacobian (units per um) carrying position noise into output units."""
    m = scn.mechanism
    step, noise_um = float(m.params.get("reading_step") or 0.0), float(m.params.get("noise_um") or 0.0)
    if not step and not noise_um:
        return None
    p, q = m.positions_mm * 1000.0, m.commands
    a, *_ = np.linalg.lstsq(np.column_stack([np.ones(len(p)), p]), q, rcond=None)
    return known_noise(q, a[1:].T, step, noise_um)


def reference_for(scn, mlp=None) -> Reference:
    """The reference of a measured scenario, fitted to every distinct mark. ``mlp``: (predict
    p_mm -> q, its held-out rows' positions, its residuals there) of the scenario's trained MLP,
    a candidate."""
    import hashlib

    m = scn.mechanism
    extra = {"mlp": mlp} if mlp is not None else {}
    key = (scn.fingerprint, hashlib.sha256(np.ascontiguousarray(mlp[2]).tobytes()).hexdigest() if mlp is not None else "")
    if key not in _CACHE:
        _CACHE.clear()
        p_rows, q_rows = m.rows
        noise = scenario_noise(scn) or repeated_noise(p_rows, q_rows)
        ref = fit_reference(m.positions_mm, m.commands, noise, extra)
        ref.extra["workspace_warning"] = hull_warning(ref.hull, scn.workspace)
        ref.extra["hull_fraction"] = ref.hull.area / float(np.prod(scn.workspace.hi - scn.workspace.lo))
        _CACHE[key] = ref
    return _CACHE[key]


def hull_warning(hull: Hull, ws) -> str | None:
    """One line when [workspace] extends beyond the marks' convex hull (None otherwise)."""
    area = float(np.prod(ws.hi - ws.lo))
    frac = hull.area / area
    if frac >= HULL_WARN:
        return None
    b = hull.to_dict()
    return (f"[workspace] x {ws.x_mm[0]:g}..{ws.x_mm[1]:g}, y {ws.y_mm[0]:g}..{ws.y_mm[1]:g} mm extends beyond the marks "
            f"(their hull spans x {b['x_mm'][0]:.4g}..{b['x_mm'][1]:.4g}, y {b['y_mm'][0]:.4g}..{b['y_mm'][1]:.4g} mm, "
            f"{100 * frac:.0f} % of it): accuracy is checked and claimed inside the hull only; outside it the C "
            "extrapolates the reference")
