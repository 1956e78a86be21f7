"""The bilinear table shared by the ``lut`` and ``hybrid`` families: grid, symmetry fold, node
fit, range analysis and the integer model (bit-exact oracle of the C).

Index (per input axis a, after the domain clamp):
    folded axis (domain symmetric about 0, every output even or odd in it): t = |x|,
    else t = x - lo;  i = t >> k (cells are 2^k input units), and the cell fraction in Q``W``
    (W = 8 or 16): v = t * 2^(16 - k) (a shift), f16 = v mod 2^16, f = f16 >> (16 - W).
    No division and no reciprocal multiply. Nodes: n = (span >> k) + 2 per axis, so i + 1 is
    always a node (the grid may extend past the domain).
Interpolation (per output, entries e int16 or int32 scaled 2^-fb, plus an offset):
    w11 = (fx fy) >> W,  a = fx - w11  (both in [0, 2^W))
    S = a (e10 - e00) + fy (e01 - e00) + w11 (e11 - e01)       (= sum w_ij (e_ij - e00), exact)
    int16: acc = e00 2^W + S, s = fb + W;   int32: acc = e00 + (S >> W), s = fb
    odd output on the negative side of a folded axis: acc = -acc
    out = offset + ((acc + 2^(s-1)) >> s) (then the DAC clamp); pre = offset + acc / 2^s.
Range analysis keeps every adjacent-node difference and every |e_ij - e00| within int16, so
S fits int32 and is computed with 16-bit differences, and |acc| + 2^(s-1) < 2^31.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.errors import NnikError

I16 = 32767
MAX_NODES = 255  # per axis: the cell index is one byte


def _truth_or_none(problem, pts):
    try:
        return problem.truth(pts)
    except NnikError:
        return None


def detect_parity(problem, n: int = 4000, seed: int = 7) -> list[list[str | None]]:
    """[output][axis] -> "even", "odd" or None, checked numerically on the exact IK at mirrored
    integer points of the problem's parity box (the symmetric hull of a field that straddles 0,
    see Problem.parity_box). Measured data has no symmetry."""
    res = [[None, None] for _ in range(2)]
    if not problem.analytic:
        return res
    lo, hi, mirror = problem.parity_box
    rng = np.random.default_rng(seed)
    pts = rng.integers(lo, hi + 1, (n, 2))
    q = problem.truth(pts)
    tol = 1e-7 * (1.0 + np.ptp(q, axis=0))
    for a in range(2):
        if not mirror[a]:
            continue
        m = pts.copy()
        m[:, a] = -m[:, a]
        qm = problem.truth(m)
        for o in range(2):
            if np.max(np.abs(qm[:, o] - q[:, o])) <= tol[o]:
                res[o][a] = "even"
            elif np.max(np.abs(qm[:, o] + q[:, o])) <= tol[o]:
                res[o][a] = "odd"
    return res


def fold_plan(problem, symmetry: bool) -> tuple[tuple[bool, bool], np.ndarray]:
    """(fold per axis, odd[o, a]): an axis is folded when every output is even or odd in it."""
    par = problem.cache.get("lut_parity")
    if par is None:
        par = problem.cache["lut_parity"] = detect_parity(problem)
    fold = tuple(bool(symmetry) and all(par[o][a] is not None for o in range(2)) for a in range(2))
    odd = np.array([[fold[a] and par[o][a] == "odd" for a in range(2)] for o in range(2)])
    return fold, odd


def dependence(problem, separable: bool) -> tuple[str, str]:
    """Per output "xy" / "x" / "y" (cached on the problem); all "xy" unless `separable`."""
    if not separable:
        return ("xy", "xy")
    dep = problem.cache.get("lut_dependence")
    if dep is None:
        dep = problem.cache["lut_dependence"] = tuple(detect_dependence(problem))
    return dep



def detect_dependence(problem, n: int = 4000, seed: int = 8) -> list[str]:
    """Per output: "xy", or "x" / "y" when the exact IK does not change with the other input
    (checked numerically at random pairs of integer points); measured data: "xy"."""
    if not problem.analytic:
        return ["xy", "xy"]
    lo, hi = problem.lo, problem.hi
    rng = np.random.default_rng(seed)
    pts = rng.integers(lo, hi + 1, (n, 2))
    q = problem.truth(pts)
    tol = 1e-7 * (1.0 + np.ptp(q, axis=0))
    dep = []
    for o in range(2):
        d = "xy"
        for a, keep in ((0, "y"), (1, "x")):
            m = pts.copy()
            m[:, a] = rng.integers(lo[a], hi[a] + 1, n)
            if np.max(np.abs(problem.truth(m)[:, o] - q[:, o])) <= tol[o]:
                d = keep
                break
        dep.append(d)
    return dep


def base_terms(odd: np.ndarray, dep) -> np.ndarray:
    """(2, 3) bool: which terms [C, Ax, Ay] of the hybrid's affine base output o may use. Odd in
    folded x: the sum must vanish at tx = 0, so no C and no Ay; likewise for y. A 1-D output
    (dep "y" / "x") has no slope along the other axis, so its residual stays 1-D."""
    use = np.ones((2, 3), dtype=bool)
    for o in range(2):
        if odd[o, 0]:
            use[o, [0, 2]] = False
        if odd[o, 1]:
            use[o, [0, 1]] = False
        if dep[o] == "y":
            use[o, 1] = False
        elif dep[o] == "x":
            use[o, 2] = False
    return use


def merge_matrix(grid, dep: str):
    """(nx*ny, n1) 0/1 matrix: node (iy, ix) -> its 1-D node (iy for "y", ix for "x")."""
    import scipy.sparse as sp

    nx, ny = grid.n
    iy, ix = np.divmod(np.arange(nx * ny), nx)
    col, n1 = (iy, ny) if dep == "y" else (ix, nx)
    return sp.csr_matrix((np.ones(nx * ny), (np.arange(nx * ny), col)), shape=(nx * ny, n1))


def _second_differences_1d(n: int):
    import scipy.sparse as sp

    if n < 3:
        return sp.csr_matrix((0, n))
    return sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n)).tocsr()


@dataclass
class Grid:
    """Index map per axis: origin, span (max t), cell exponent k, nodes n, folded or not."""

    origin: tuple[int, int]
    span: tuple[int, int]
    k: tuple[int, int]
    n: tuple[int, int]
    fold: tuple[bool, bool]
    W: int

    @classmethod
    def make(cls, lo, hi, k, fold, W) -> "Grid":
        origin, span, n = [], [], []
        for a in range(2):
            if fold[a]:  # t = |x|: the stored half reaches the farther edge
                origin.append(0)
                span.append(max(int(hi[a]), -int(lo[a])))
            else:
                origin.append(int(lo[a]))
                span.append(int(hi[a] - lo[a]))
            if not 0 <= k[a] <= 22:
                raise NnikError(f"cell exponent {k[a]} out of range 0..22")
            n.append((span[a] >> k[a]) + 2)
            if n[a] > MAX_NODES:
                raise NnikError(f"{n[a]} nodes on axis {a} (cells of 2^{k[a]} units): at most {MAX_NODES}")
            if span[a] >= 2**23:
                raise NnikError("domain span exceeds 2^23 input units")
        if W not in (8, 16):
            raise NnikError(f"weight bits {W}: must be 8 or 16")
        return cls(tuple(origin), tuple(span), tuple(int(v) for v in k), tuple(n), tuple(bool(f) for f in fold), W)

    def t(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Clamped integer inputs (N, 2) -> (t (N, 2) int64, negative side (N, 2) bool)."""
        c = np.asarray(c, dtype=np.int64)
        neg = np.zeros(c.shape, dtype=bool)
        t = np.empty_like(c)
        for a in range(2):
            if self.fold[a]:
                neg[:, a] = c[:, a] < 0
                t[:, a] = np.abs(c[:, a])
            else:
                t[:, a] = c[:, a] - self.origin[a]
        return t, neg

    def index(self, t: np.ndarray) -> tuple[list, list]:
        """(i per axis, f per axis in Q W) for integer t."""
        ii, ff = [], []
        for a in range(2):
            k = self.k[a]
            ta = t[:, a]
            i = ta >> k
            f16 = ((ta >> (k - 16)) if k >= 16 else (ta << (16 - k))) & 0xFFFF
            ii.append(i)
            ff.append(f16 >> (16 - self.W))
        return ii, ff

    def basis(self, t_float: np.ndarray):
        """Sparse rows (N, nx*ny) of interpolation weights at real-valued t (integer t gives the
        integer model's weights exactly, /2^W): node (iy, ix) is column iy*nx + ix."""
        import scipy.sparse as sp

        t = np.asarray(t_float, dtype=np.float64)
        ii, ff = [], []
        for a in range(2):
            ta = np.clip(t[:, a], 0, self.span[a])
            i = np.floor(ta / 2.0 ** self.k[a]).astype(np.int64)
            f = np.floor((ta - i * 2.0 ** self.k[a]) * 2.0 ** (self.W - self.k[a]))
            ii.append(i)
            ff.append(np.clip(f, 0, 2**self.W - 1).astype(np.int64))
        (ix, iy), (fx, fy) = ii, ff
        w11 = (fx * fy) >> self.W
        one = 1 << self.W
        ws = [one - fx - fy + w11, fx - w11, fy - w11, w11]
        nx = self.n[0]
        cols = [iy * nx + ix, iy * nx + ix + 1, (iy + 1) * nx + ix, (iy + 1) * nx + ix + 1]
        rows = np.tile(np.arange(len(t)), 4)
        return sp.csr_matrix((np.concatenate(ws) / one, (rows, np.concatenate(cols))),
                             shape=(len(t), self.n[0] * self.n[1]))


def second_differences(nx: int, ny: int):
    import scipy.sparse as sp

    def d2(n):
        if n < 3:
            return sp.csr_matrix((0, n))
        return sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n))

    return sp.vstack([sp.kron(sp.eye(ny), d2(nx)), sp.kron(d2(ny), sp.eye(nx))]).tocsr()


def _solve_lsq(a, d, q, lam: float, fixed: np.ndarray) -> np.ndarray:
    """min |a v - q|^2 + lam^2 |d v|^2 over the free nodes (fixed nodes are 0)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    free = ~fixed
    af, df = a[:, free], d[:, free]
    m = (af.T @ af + (lam**2) * (df.T @ df)).tocsc()
    m = m + sp.identity(m.shape[0], format="csc") * 1e-12 * max(1.0, m.diagonal().max())
    v = np.zeros(a.shape[1])
    v[free] = spsolve(m, af.T @ q)
    return v


def _solve_minimax(a, q, v0: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """min max |a v - q| (scipy.optimize.linprog, HiGHS), nodes boxed around the LSQ solution."""
    import scipy.sparse as sp
    from scipy.optimize import linprog

    free = ~fixed
    af = a[:, free].tocsr()
    nf = af.shape[1]
    r0 = float(np.abs(a @ v0 - q).max())
    ones = sp.csr_matrix(np.ones((af.shape[0], 1)))
    a_ub = sp.vstack([sp.hstack([af, -ones]), sp.hstack([-af, -ones])]).tocsr()
    b_ub = np.concatenate([q, -q])
    c = np.zeros(nf + 1)
    c[-1] = 1.0
    box = 4.0 * r0 + 1e-9
    bounds = [(x - box, x + box) for x in v0[free]] + [(0, None)]
    r = linprog(c, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if r.status != 0:
        raise NnikError(f"minimax fit failed: {r.message}")
    v = np.zeros(a.shape[1])
    v[free] = r.x[:-1]
    return v


SMOOTH_GRID = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0)


def choose_smooth(a, d, q, fixed, folds: int = 5, seed: int = 0) -> float:
    """Smoothness weight with the least k-fold cross-validated squared error on measured rows."""
    part = np.random.default_rng(seed).permutation(a.shape[0]) % folds
    best = None
    for lam in SMOOTH_GRID:
        sse = 0.0
        for f in range(folds):
            tr, te = part != f, part == f
            v = _solve_lsq(a[tr], d, q[tr], lam, fixed)
            sse += float(((a[te] @ v - q[te]) ** 2).sum())
        if best is None or sse < best[0]:
            best = (sse, lam)
    return best[1]


def fit_nodes(grid: Grid, t: np.ndarray, q: np.ndarray, odd: np.ndarray, method: str, measured: bool,
              smooth: float | None = None, dep=("xy", "xy")) -> tuple[np.ndarray, dict]:
    """Node values (2, ny, nx) fitted to targets q (N, 2) at folded coordinates t (N, 2).
    odd[o, a]: output o is odd in folded axis a, so its nodes at t_a = 0 are fixed to 0.
    dep[o] = "x" / "y": a 1-D table along that axis (the 2-D basis with its columns merged is
    exactly the 1-D interpolation), replicated along the other axis."""
    a2 = grid.basis(t).tocsr()
    d2 = second_differences(*grid.n)
    nx, ny = grid.n
    vals = np.empty((2, ny, nx))
    info = {}
    for o in range(2):
        fixed = np.zeros((ny, nx), dtype=bool)
        if odd[o, 0]:
            fixed[:, 0] = True
        if odd[o, 1]:
            fixed[0, :] = True
        fixed = fixed.ravel()
        a, d, merge = a2, d2, None
        if dep[o] in ("x", "y"):
            merge = merge_matrix(grid, dep[o])
            a = (a2 @ merge).tocsr()
            d = _second_differences_1d(merge.shape[1])
            fixed = (merge.T @ fixed.astype(float)) > 0
        if measured:
            lam = choose_smooth(a, d, q[:, o], fixed) if smooth is None else smooth
            info[f"smooth{o}"] = lam
        else:
            # a whisper of smoothness only to extrapolate nodes no sample touches
            lam = 1e-6 if smooth is None else smooth
        v = _solve_lsq(a, d, q[:, o], lam, fixed)
        if method == "minimax":
            v = _solve_minimax(a, q[:, o], v, fixed)
        elif method != "lsq":
            raise NnikError(f"unknown fit method {method!r} (lsq | minimax)")
        vals[o] = (merge @ v if merge is not None else v).reshape(ny, nx)
    return vals, info


@dataclass
class Table:
    """A quantised bilinear table (see the module docstring)."""

    grid: Grid
    bits: int  # entry width, 16 | 32
    fb: tuple[int, int]  # fractional bits per output
    offset: tuple[int, int]  # per output, output units (added after the rounding shift)
    odd: np.ndarray  # (2, 2) bool: output o flips sign on the negative side of folded axis a
    ent: np.ndarray  # (2, ny, nx) int64 (a 1-D output's entries replicated along the other axis)
    dep: tuple[str, str] = ("xy", "xy")  # per output: "xy", or a 1-D table along "x" / "y"

    def stored(self, o: int) -> np.ndarray:
        """The entries output o keeps in flash: [y][x], or one row/column for a 1-D table."""
        e = self.ent[o]
        return e[:, 0] if self.dep[o] == "y" else e[0, :] if self.dep[o] == "x" else e.ravel()

    @property
    def shift(self) -> tuple[int, int]:
        """s per output: acc / 2^s is the value (before the offset)."""
        return tuple(self.fb[o] + (self.grid.W if self.bits == 16 else 0) for o in range(2))

    @property
    def nbytes(self) -> int:
        return int(sum(self.stored(o).size for o in range(2)) * self.bits // 8)

    def acc(self, c: np.ndarray, flip: bool = True) -> np.ndarray:
        """Clamped inputs (N, 2) -> acc (N, 2) int64 (value 2^-s, before the offset); with
        flip=False the odd outputs' negation is left to the caller (the hybrid adds its base
        first)."""
        g = self.grid
        t, neg = g.t(c)
        (ix, iy), (fx, fy) = g.index(t)
        W = g.W
        w11 = (fx * fy) >> W
        aw = fx - w11
        out = np.empty(t.shape, dtype=np.int64)
        for o in range(2):
            e = self.ent[o]
            e00, e10 = e[iy, ix], e[iy, ix + 1]
            e01, e11 = e[iy + 1, ix], e[iy + 1, ix + 1]
            s = aw * (e10 - e00) + fy * (e01 - e00) + w11 * (e11 - e01)
            assert np.abs(s).max(initial=0) < 2**31
            acc = e00 * (1 << W) + s if self.bits == 16 else e00 + (s >> W)
            out[:, o] = np.where(self.flips(neg, o), -acc, acc) if flip else acc
        return out

    def flips(self, neg: np.ndarray, o: int) -> np.ndarray:
        """(N,) bool: output o is negated (odd in a folded axis whose input is negative)."""
        f = np.zeros(len(neg), dtype=bool)
        for a in range(2):
            if self.odd[o, a]:
                f ^= neg[:, a]
        return f


def quantise(grid: Grid, vals: np.ndarray, bits: int, odd: np.ndarray, fb_force: int | None = None,
             dep=("xy", "xy")) -> Table:
    """Range analysis: the offset and the most fractional bits per output such that entries fit
    their type, every adjacent difference and every |e_ij - e00| fits int16 and
    |acc| + 2^(s-1) < 2^31. Raises NnikError when even fb = 0 (or the forced fb) overflows."""
    if bits not in (16, 32):
        raise NnikError(f"entry bits {bits}: must be 16 or 32")
    W = grid.W
    ents, fbs, offs = [], [], []
    for o in range(2):
        v = vals[o]
        off = 0 if odd[o].any() else int(np.rint((v.max() + v.min()) / 2))
        cands = [fb_force] if fb_force is not None else list(range(30, -1, -1))
        chosen = None
        for fb in cands:
            e = np.rint((v - off) * 2.0**fb)
            if _fits(e, bits, W, fb):
                chosen = (fb, e.astype(np.int64))
                break
        if chosen is None:
            what = f"with {fb_force} fractional bits" if fb_force is not None else "even with 0 fractional bits"
            raise NnikError(f"table overflows {what}: output {o} needs int{bits} entries and int16 node "
                            f"differences (range {v.min():.6g}..{v.max():.6g}, cells 2^{grid.k[0]} x 2^{grid.k[1]})")
        fbs.append(chosen[0])
        ents.append(chosen[1])
        offs.append(off)
    return Table(grid=grid, bits=bits, fb=tuple(fbs), offset=tuple(offs), odd=np.asarray(odd, bool),
                 ent=np.stack(ents), dep=tuple(dep))


def _fits(e: np.ndarray, bits: int, W: int, fb: int) -> bool:
    emax = float(np.abs(e).max())
    dx = np.abs(np.diff(e, axis=1)).max(initial=0)
    dy = np.abs(np.diff(e, axis=0)).max(initial=0)
    dd = np.abs(e[1:, 1:] - e[:-1, :-1]).max(initial=0)
    if max(dx, dy, dd) > I16:
        return False
    s = fb + (W if bits == 16 else 0)
    half = 2.0 ** (s - 1) if s > 0 else 0.0
    if bits == 16:
        return emax <= I16 and emax * 2.0**W + half < 2.0**31
    return emax + 32768.0 + half < 2.0**31 - 1
