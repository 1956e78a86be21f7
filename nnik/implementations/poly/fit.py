"""The `poly` family's real-valued half: input normalisation, symmetry detection from the
problem's own truth, the monomial set it allows, and the fit (minimax by linear programming, or
least squares).

Normalisation (done in integers by the C): ``d = x - c`` with ``c`` the domain centre rounded
down (0 when the workspace is symmetric about 0), then ``u = d >> k`` (``k >= 0``, floor) or
``u = d << -k``: an int16 with ``|u| <= 32767``; the polynomial's variable is ``t = u / 2^15``.

Symmetry: for an analytic mechanism, each output is split into its parity components by
sampling the truth at mirrored points, about x = 0 (y = 0) only when that is the domain centre.
A component that vanishes drops its monomials; an output equal at (x, y) and (x', y) does not
depend on x. Measured data get no symmetry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.problem import Problem

SYM_TOL = 1e-7  # a component is zero below this fraction of the output's range (+1 unit)


@dataclass(frozen=True)
class AxisMap:
    """u = (x - c) >> k (k >= 0, floor) or (x - c) << -k."""

    c: int
    k: int

    def u(self, x: np.ndarray) -> np.ndarray:
        d = np.asarray(x, dtype=np.int64) - self.c
        return d >> self.k if self.k >= 0 else d << -self.k

    def r(self, x: np.ndarray) -> np.ndarray:
        """The bits the shift drops: d & (2^k - 1) (0 when k <= 0)."""
        d = np.asarray(x, dtype=np.int64) - self.c
        return d & ((1 << self.k) - 1) if self.k > 0 else np.zeros_like(d)


def axis_maps(p: Problem) -> list[AxisMap]:
    maps = []
    mirror = p.parity_box[2]
    for a in range(2):
        lo, hi = int(p.lo[a]), int(p.hi[a])
        c = 0 if mirror[a] else (lo + hi) // 2  # centred on 0 where the IK's parity is tested
        dmax = max(hi - c, c - lo, 1)
        k = 0
        while dmax > 32767 * 2**k:
            k += 1
        if k == 0:
            while dmax * 2 ** (-k + 1) <= 32767:
                k -= 1
        maps.append(AxisMap(c, k))
    return maps


def t_of(p: Problem, x_units: np.ndarray) -> np.ndarray:
    """(N, 2) integer inputs -> (N, 2) normalised t = u / 2^15 (after the C's clamp)."""
    c, _ = p.clamp(x_units)
    maps = axis_maps(p)
    return np.stack([maps[a].u(c[:, a]) for a in range(2)], 1) / 32768.0


def delta_of(p: Problem, x_units: np.ndarray) -> np.ndarray:
    """(N, 2): what the shift dropped, in units of t: r / 2^(15 + k)."""
    c, _ = p.clamp(x_units)
    maps = axis_maps(p)
    return np.stack([maps[a].r(c[:, a]) / 2.0 ** (15 + max(maps[a].k, 0)) for a in range(2)], 1)


# ---- symmetry ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Symmetry:
    """Per output: which parity classes (i % 2, j % 2) of u^i v^j are present (None = the axis is
    not symmetric about the domain centre: any parity), and whether it depends on x / y."""

    classes: tuple  # frozenset of (px, py) with px, py in {0, 1, None}
    indep_x: bool
    indep_y: bool

    def allows(self, i: int, j: int) -> bool:
        if self.indep_x and i:
            return False
        if self.indep_y and j:
            return False
        for px, py in self.classes:
            if (px is None or px == i % 2) and (py is None or py == j % 2):
                return True
        return False

    def label(self) -> str:
        def axis(name, indep, idx):
            if indep:
                return f"independent of {name}"
            pars = {c[idx] for c in self.classes}
            if pars == {1}:
                return f"odd in {name}"
            if pars == {0}:
                return f"even in {name}"
            return None
        parts = [s for s in (axis("x", self.indep_x, 0), axis("y", self.indep_y, 1)) if s]
        return ", ".join(parts) if parts else "no symmetry"


NO_SYMMETRY = Symmetry(frozenset({(None, None)}), False, False)


def detect_symmetry(p: Problem, n: int = 4096, seed: int = 7) -> list[Symmetry]:
    """Per output, from the truth at n random in-domain points and their mirror images."""
    if not p.analytic:
        return [NO_SYMMETRY, NO_SYMMETRY]
    lo, hi, mirror = p.parity_box  # the symmetric hull of the field: parity belongs to the IK
    rng = np.random.default_rng(seed)
    pts = rng.integers(lo, hi + 1, (n, 2))
    f = p.truth(pts)
    tol = SYM_TOL * (np.ptp(f, axis=0) + 1.0)
    sym = list(mirror)
    # independence of x (y): the truth does not change when x (y) is redrawn
    indep = []
    for a in range(2):
        q = pts.copy()
        q[:, a] = rng.integers(lo[a], hi[a] + 1, n)
        indep.append(np.all(np.abs(p.truth(q) - f) <= tol, axis=0))
    # parity components on the symmetric axes: average over the mirror images with signs
    mir = {}
    for sx in ((1, -1) if sym[0] else (1,)):
        for sy in ((1, -1) if sym[1] else (1,)):
            mir[(sx, sy)] = f if (sx, sy) == (1, 1) else p.truth(pts * np.array([sx, sy]))
    f00 = p.truth(np.zeros((1, 2), dtype=np.int64) + np.where(sym, 0, lo))[0]
    out = []
    for o in range(2):
        classes = set()
        pxs = (0, 1) if sym[0] else (None,)
        pys = (0, 1) if sym[1] else (None,)
        for px in pxs:
            for py in pys:
                comp = np.zeros(n)
                for (sx, sy), v in mir.items():
                    sign = (sx if px == 1 else 1) * (sy if py == 1 else 1)
                    comp += sign * v[:, o]
                comp /= len(mir)
                if px in (0, None) and py in (0, None):
                    comp = comp - f00[o]  # the constant term is always kept
                if np.abs(comp).max() > tol[o]:
                    classes.add((px, py))
        if not classes:
            classes.add((0 if sym[0] else None, 0 if sym[1] else None))
        out.append(Symmetry(frozenset(classes), bool(indep[0][o]), bool(indep[1][o])))
    return out


# ---- monomials and fit -------------------------------------------------------------------------

def monomials(sym: Symmetry, degree: int, dx: int | None = None, dy: int | None = None) -> list[tuple[int, int]]:
    """(i, j) of the non-constant terms u^i v^j allowed by the degree limits and the symmetry."""
    dx = degree if dx is None else dx
    dy = degree if dy is None else dy
    return [(i, j) for i in range(dx + 1) for j in range(dy + 1)
            if 0 < i + j <= degree and sym.allows(i, j)]


def fit_data(p: Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t (N, 2), truth (N, 2), delta (N, 2)) at integer inputs: problem.fit_samples() rounded
    to input units."""
    key = ("poly_fit_data",)
    if key not in p.cache:
        x, q = p.fit_samples()
        xi = np.clip(np.rint(x).astype(np.int64), p.lo, p.hi)
        if p.analytic:
            xi = np.unique(xi, axis=0)
            q = p.truth(xi)
        p.cache[key] = (t_of(p, xi), np.asarray(q, dtype=np.float64), delta_of(p, xi))
    return p.cache[key]


def design(t: np.ndarray, terms: list[tuple[int, int]], extra: np.ndarray | None = None) -> np.ndarray:
    cols = [np.ones(len(t))] + [t[:, 0] ** i * t[:, 1] ** j for i, j in terms]
    if extra is not None:
        cols += list(extra.T)
    return np.stack(cols, 1)


def fit_poly(t: np.ndarray, q: np.ndarray, terms: list[tuple[int, int]], how: str,
             extra: np.ndarray | None = None) -> np.ndarray:
    """Coefficients [c00, c_terms..., c_extra...] of q ~ c00 + sum c_ij t_x^i t_y^j
    (+ sum c_k extra_k: the dropped input bits) (L-inf or L2)."""
    a = design(t, terms, extra)
    scale = np.abs(a).max(0)
    scale[scale == 0] = 1.0
    a_s = a / scale
    mid = 0.5 * (q.max() + q.min())
    rng = max(float(np.ptp(q)), 1e-12)
    y = (q - mid) / rng
    c, *_ = np.linalg.lstsq(a_s, y, rcond=None)
    if how == "minimax":
        from scipy.optimize import linprog

        n, m = a_s.shape
        # min tau  s.t.  A c - y <= tau,  -(A c - y) <= tau
        ones = np.ones((n, 1))
        a_ub = np.block([[a_s, -ones], [-a_s, -ones]])
        b_ub = np.concatenate([y, -y])
        cost = np.zeros(m + 1)
        cost[-1] = 1.0
        res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * (m + 1), method="highs")
        if res.status != 0:
            raise NnikError(f"poly: minimax fit failed ({res.message})")
        c = res.x[:m]
    elif how != "lsq":
        raise NnikError(f"poly: unknown fit {how!r} (minimax | lsq)")
    c = c * rng / scale
    c[0] += mid
    return c
