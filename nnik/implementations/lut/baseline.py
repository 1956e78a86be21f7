"""The old LUT baseline: a second bilinear table with its own integer contract, written beside
the ``lut`` family when the MLP was the product (``NAME_lut.c``, the report's "baseline: LUT"
rows). It is to be retired into the ``lut`` family; until then it lives here, with its family.

It emits ``int8_t NAME_lut_ik(const int32_t in_um[2], int32_t out[2])`` with the contract of
:mod:`nnik.targets.float_ik`.

LUT (:func:`build_lut`, :func:`lut_int`, :func:`render_lut_c`)
    An nx x ny grid of nodes per output, bilinear interpolation, integers only. Integer contract
    (the C and :func:`lut_int` agree bit for bit):

    * clamp each input to [lo, hi] (int32), ``t = x - lo`` as uint32 (0 <= t <= span);
    * ``pos = (t * R) >> b`` with R a uint16 reciprocal (``t * R < 2^32``): the position in
      cells, Q15. ``i = pos >> 15``, ``f = pos & 32767``; if ``i`` reaches the cell count
      (only possible exactly at the far edge) ``i = ncell - 1, f = 32768``. R is rounded down,
      so the grid covers the domain; node j sits where ``pos = j * 2^15``, that is at
      ``t_j = j 2^(15+b) / R`` micrometres, and its value is taken there (the grid may end a
      few micrometres beyond the domain, never short of it);
    * weights in Q``W`` (W = 15 for int16 entries): ``w11 = (fx fy) >> W``,
      ``w10 = fx - w11``, ``w01 = fy - w11``, ``w00 = 2^W - fx - fy + w11``; all in
      [0, 2^W] (uint16) and summing exactly to 2^W (fx, fy are first shifted right by 15 - W
      when W < 15);
    * ``acc = e00 w00 + e10 w10 + e01 w01 + e11 w11`` in int32; int16 entries make these four
      signed x unsigned 16x16 -> 32 products (|acc| <= 2^30);
    * entry e encodes ``offset + e 2^-k`` units, so
      ``out = offset + ((acc + 2^(s-1)) >> s)`` with ``s = k + W`` (arithmetic shift),
      then the DAC clamp. ``pre = offset + acc / 2^s`` is the value before rounding.

    int16 entries when the output range allows (k >= 0 chosen as large as fits), else int32
    entries (k = 0) with W reduced so that |acc| < 2^30. No int64, no left shift of a negative
    value, no division in the C.

    Node values: the exact IK (:func:`nnik.machine.data.exact_targets`) for analytic mechanisms; for
    ``measured``, a regularised least-squares fit of the bilinear surface to the training rows
    (second-difference smoothness, so the affine part is not biased), solved with
    ``scipy.sparse.linalg.lsqr`` -- the calibration-table approach.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nnik.emit.templating import environment
from nnik.errors import NnikError
from nnik.machine.scenario import Scenario
from nnik.emit.c_text import c_comment_safe
from nnik.machine.domain import domain_um
from nnik.targets.float_ik import _check_name, _domain_ctx, _i32

FRAC_BITS = 15  # cell fraction, Q15: weights in [0, 2^15] fit uint16, products are 16x16 -> 32
K_MAX = 15  # most fractional bits kept in an int16 entry (keeps acc + 2^(s-1) < 2^31)
MAX_ENTRIES = 32767  # the C indexes the table with uint16 arithmetic


@dataclass
class Lut:
    """A bilinear lookup table with its integer index mapping (see the module docstring)."""

    scenario: str
    unit: str
    outputs: list[str]
    lo_um: np.ndarray  # (2,) int64, the clamp domain
    hi_um: np.ndarray
    nx: int
    ny: int
    recip: tuple[int, int]  # R per axis (uint16)
    shift: tuple[int, int]  # b per axis
    entry_bits: int  # 16 | 32
    wbits: int  # W, weight precision (15 for int16 entries)
    k: tuple[int, int]  # fractional bits of the entries, per output
    offset: tuple[int, int]  # per output, units
    table: np.ndarray  # (ny, nx, 2) int64 entries
    code_range: tuple[int, int] | None
    budget_bytes: int
    origin: str  # how the node values were obtained
    node_um: tuple[np.ndarray, np.ndarray] = field(repr=False, default=None)  # node offsets from lo (float um)
    values: np.ndarray = field(repr=False, default=None)  # (ny, nx, 2) node values before quantisation

    @property
    def flash_bytes(self) -> int:
        """Bytes of table data (the code around it is not counted)."""
        return int(self.table.size * self.entry_bits // 8)

    @property
    def ncell(self) -> tuple[int, int]:
        return (self.nx - 1, self.ny - 1)


def _axis_map(span: int, ncell: int) -> tuple[int, int]:
    """(R, b): pos = (t R) >> b approximates t ncell 2^15 / span from below, R <= 65535 and
    span R < 2^32, b as large as possible."""
    if span <= 0:
        raise NnikError(f"empty input domain (span {span} um)")
    rmax = min(65535, (2**32 - 1) // span)
    num = ncell << FRAC_BITS
    if num // span > rmax:
        raise NnikError(f"{ncell} cells over {span} um: cells narrower than the index map resolves")
    b = 0
    while b < 31 and (num << (b + 1)) // span <= rmax:
        b += 1
    r = (num << b) // span
    if r < 1:
        raise NnikError(f"{ncell} cells over {span} um: no usable reciprocal")
    return int(r), int(b)


def _node_offsets(ncell: int, r: int, b: int) -> np.ndarray:
    """Node j's offset from lo in um: where pos = j 2^15, i.e. t = j 2^(15+b) / R."""
    return np.arange(ncell + 1) * (2.0 ** (FRAC_BITS + b) / r)


def _quantise(values: np.ndarray, entry_bits: int):
    """Node values (ny, nx, 2) in units -> (entries, k, offset, W) or None if int16 cannot hold them."""
    ks, offs, ents = [], [], []
    for o in range(values.shape[2]):
        v = values[:, :, o]
        off = int(np.rint((v.max() + v.min()) / 2))
        if entry_bits == 16:
            k = None
            for kk in range(K_MAX, -1, -1):
                e = np.rint((v - off) * 2.0**kk)
                if e.min() >= -32768 and e.max() <= 32767:
                    k = kk
                    break
            if k is None:
                return None
        else:
            k = 0
            e = np.rint(v - off)
        ks.append(k)
        offs.append(off)
        ents.append(e.astype(np.int64))
    ent = np.stack(ents, 2)
    if entry_bits == 16:
        w = FRAC_BITS
    else:
        w = min(FRAC_BITS, 30 - int(np.abs(ent).max()).bit_length())
        if w < 1:
            raise NnikError("output range too large for an int32 table")
    return ent, tuple(ks), tuple(offs), w


def _make_lut(lo, hi, nx, ny, values_fn, entry_bits, code_range, budget, origin, meta) -> Lut | None:
    span = (hi - lo).astype(np.int64)
    (rx, bx), (ry, by) = _axis_map(int(span[0]), nx - 1), _axis_map(int(span[1]), ny - 1)
    ox, oy = _node_offsets(nx - 1, rx, bx), _node_offsets(ny - 1, ry, by)
    values = values_fn(ox, oy, (rx, bx), (ry, by))  # (ny, nx, 2)
    q = _quantise(values, entry_bits)
    if q is None:
        return None
    ent, ks, offs, w = q
    return Lut(scenario=meta["name"], unit=meta["unit"], outputs=meta["outputs"], lo_um=lo, hi_um=hi,
               nx=nx, ny=ny, recip=(rx, ry), shift=(bx, by), entry_bits=entry_bits, wbits=w, k=ks,
               offset=offs, table=ent, code_range=code_range, budget_bytes=budget, origin=origin,
               node_um=(ox, oy), values=values)


def _grid_candidates(nodes: int, span: np.ndarray, analytic: bool) -> list[tuple[int, int]]:
    """(nx, ny) with nx, ny >= 2, nx ny <= nodes: all useful ones (capped) for a search, or
    the one that best matches the workspace's aspect ratio."""
    if nodes < 4:
        return []
    cands = []
    for nx in range(2, nodes // 2 + 1):
        ny = nodes // nx
        if ny >= 2:
            cands.append((nx, ny))
    # drop dominated shapes: for each ny keep only the largest nx
    best_nx = {}
    for nx, ny in cands:
        best_nx[ny] = max(nx, best_nx.get(ny, 0))
    cands = sorted((nx, ny) for ny, nx in best_nx.items())
    if analytic:
        if len(cands) > 48:
            idx = np.unique(np.rint(np.geomspace(1, len(cands), 48)).astype(int) - 1)
            cands = [cands[i] for i in idx]
        return cands
    aspect = span[0] / span[1]
    return [min(cands, key=lambda c: (abs(np.log((c[0] - 1) / (c[1] - 1) / aspect)), -c[0] * c[1]))]


def _bilinear_basis(p_mm, lo, ox, oy, maps):
    """Rows of the bilinear interpolation matrix at p (mm) for nodes at offsets ox, oy (um)."""
    import scipy.sparse as sp

    nx, ny = len(ox), len(oy)
    t = p_mm * 1000.0 - lo
    cols, ws = [], []
    idx = []
    for a, (n, (r, b)) in enumerate(((nx, maps[0]), (ny, maps[1]))):
        c = np.clip(t[:, a], 0, None) * r / 2.0 ** (FRAC_BITS + b)  # continuous cell coordinate
        i = np.clip(np.floor(c).astype(np.int64), 0, n - 2)
        idx.append((i, c - i))
    (ix, fx), (iy, fy) = idx
    rows = np.arange(len(p_mm))
    for dx, dy, w in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy), (1, 1, fx * fy)):
        cols.append((iy + dy) * nx + ix + dx)
        ws.append(w)
    return sp.csr_matrix((np.concatenate(ws), (np.tile(rows, 4), np.concatenate(cols))), shape=(len(p_mm), nx * ny))


def _second_differences(nx, ny):
    import scipy.sparse as sp

    def d2(n):
        if n < 3:
            return sp.csr_matrix((0, n))
        return sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n))

    return sp.vstack([sp.kron(sp.eye(ny), d2(nx)), sp.kron(d2(ny), sp.eye(nx))]).tocsr()


def _normal_equations(p_mm, q, lo, ox, oy, maps):
    """(A^T A, A^T q) of the bilinear interpolation matrix A at the rows: O(rows) once, after
    which every smoothness weight is a small sparse solve (10^6 rows take seconds)."""
    a = _bilinear_basis(np.asarray(p_mm, float), lo, ox, oy, maps)
    return (a.T @ a).tocsc(), a.T @ np.asarray(q, float)


def _solve_nodes(gram, rhs, d, smooth, x0, shape) -> np.ndarray:
    """argmin |A x - q|^2 + smooth^2 |D x|^2, nearest x0 where the rows leave it free."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    m = (gram + smooth**2 * (d.T @ d)).tocsc()
    ridge = 1e-12 * max(float(m.diagonal().mean()), 1e-300)  # only decides directions nothing fixes
    m = (m + ridge * sp.eye(m.shape[0], format="csc")).tocsc()
    out = np.empty((*shape, rhs.shape[1]))
    for o in range(rhs.shape[1]):
        sol = spsolve(m, rhs[:, o] - gram @ x0[o] - smooth**2 * (d.T @ (d @ x0[o]))) + x0[o]
        out[:, :, o] = sol.reshape(shape)
    return out


def fit_nodes_lsq(p_mm, q, lo, ox, oy, maps, smooth: float = 0.05) -> np.ndarray:
    """Node values (ny, nx, 2) of the bilinear surface closest to the rows (p_mm, q), with a
    second-difference penalty of weight `smooth` (units per unit of second difference)."""
    nx, ny = len(ox), len(oy)
    q = np.asarray(q, float)
    gram, rhs = _normal_equations(p_mm, q, lo, ox, oy, maps)
    x0 = [np.full(nx * ny, np.mean(q[:, o])) for o in range(q.shape[1])]
    return _solve_nodes(gram, rhs, _second_differences(nx, ny), smooth, x0, (ny, nx))


SMOOTH_GRID = (0.03, 0.1, 0.3, 1.0, 3.0, 10.0)
CV_FOLDS = 5


def choose_smooth(p_mm, q, lo, ox, oy, maps, grid=SMOOTH_GRID, folds=CV_FOLDS, seed=0) -> float:
    """The smoothness weight with the smallest k-fold cross-validated RMS error on the rows."""
    p_mm, q = np.asarray(p_mm, float), np.asarray(q, float)
    nx, ny = len(ox), len(oy)
    part = np.random.default_rng(seed).permutation(len(q)) % folds
    d = _second_differences(nx, ny)
    held = [_normal_equations(p_mm[part == f], q[part == f], lo, ox, oy, maps) for f in range(folds)]
    gram_all, rhs_all = sum(g for g, _ in held), sum(r for _, r in held)
    best = None
    for lam in grid:
        sse = 0.0
        for f in range(folds):
            tr, te = part != f, part == f
            x0 = [np.full(nx * ny, np.mean(q[tr, o])) for o in range(q.shape[1])]
            v = _solve_nodes(gram_all - held[f][0], rhs_all - held[f][1], d, lam, x0, (ny, nx))
            a = _bilinear_basis(p_mm[te], lo, ox, oy, maps)
            pred = np.stack([a @ v[:, :, o].ravel() for o in range(2)], 1)
            sse += float(((pred - q[te]) ** 2).sum())
        if best is None or sse < best[0]:
            best = (sse, lam)
    return best[1]


def build_lut(scn: Scenario, budget_bytes: int, train_p_mm: np.ndarray | None = None,
              train_q: np.ndarray | None = None, smooth: float | None = None) -> Lut:
    """The most accurate bilinear table whose entries fit in `budget_bytes`
    (2 outputs x nx x ny x bytes per entry).

    Analytic mechanisms: node values are the exact IK; among the grid shapes that fill the budget
    the one with the smallest max error of :func:`lut_int` before rounding, on 4096 probe
    points, wins (the Q15 cell fraction matters on coarse grids of belt machines).
    Measured: node values fitted to (train_p_mm, train_q) -- by default the train split of
    :func:`nnik.machine.data.build_dataset` -- on the grid matching the workspace's aspect ratio, with
    the smoothness weight `smooth` (None: chosen by 5-fold cross-validation on those rows).
    """
    from nnik.machine.data import exact_targets

    lo, hi = domain_um(scn.workspace)
    span = hi - lo
    m = scn.mechanism
    meta = {"name": scn.name, "unit": scn.unit, "outputs": scn.outputs}
    code_range = scn.actuator.code_range
    if m.analytic:
        def values_fn(ox, oy, mx, my):
            gx, gy = np.meshgrid(lo[0] + ox, lo[1] + oy, indexing="xy")
            p = np.stack([gx.ravel(), gy.ravel()], 1) / 1000.0
            return exact_targets(scn, p).reshape(len(oy), len(ox), 2)
        probe_um = np.rint(_probe_points(scn) * 1000).astype(np.int64)
        q_range = exact_targets(scn, probe_um / 1000.0)
        origin = "exact IK at the nodes"
    else:
        if train_p_mm is None or train_q is None:
            from nnik.machine.data import build_dataset

            ds = build_dataset(scn)
            train_p_mm, train_q = ds.p["train"], ds.q["train"]
        train_p_mm, train_q = np.asarray(train_p_mm, float), np.asarray(train_q, float)

        chosen = {}

        def values_fn(ox, oy, mx, my):
            lam = smooth
            if lam is None:
                lam = choose_smooth(train_p_mm, train_q, lo, ox, oy, (mx, my))
            chosen["smooth"] = lam
            return fit_nodes_lsq(train_p_mm, train_q, lo, ox, oy, (mx, my), lam)
        q_range = train_q
        origin = f"least squares on {len(train_q)} measured rows"
    wide = np.ptp(q_range, axis=0).max() * 1.02 + 2 > 65535
    last_err = None
    for bits in ((32,) if wide else (16, 32)):
        nodes = min(budget_bytes // (2 * bits // 8), MAX_ENTRIES // 2)
        cands = _grid_candidates(nodes, span.astype(float), m.analytic)
        if not cands:
            last_err = f"budget of {budget_bytes} bytes holds fewer than 2 x 2 nodes"
            continue
        best = None
        for nx, ny in cands:
            try:
                lut = _make_lut(lo, hi, nx, ny, values_fn, bits, code_range, budget_bytes, origin, meta)
            except NnikError as exc:
                last_err = str(exc)
                continue
            if lut is None:
                continue
            if len(cands) == 1:
                if not m.analytic:
                    how = "given" if smooth is not None else "chosen by 5-fold cross-validation"
                    lut.origin += f" (second-difference smoothness {chosen['smooth']:g}, {how})"
                return lut
            err = np.abs(lut_int(lut, probe_um)[2] - q_range)  # the integer table, before rounding
            score = (float(err.max()), float(np.sqrt((err**2).mean())))
            if best is None or score < best[0]:
                best = (score, lut)
        if best is not None:
            return best[1]
    raise NnikError(f"no lookup table fits: {last_err or 'output range too large'}", scn.source)


def _probe_points(scn: Scenario) -> np.ndarray:
    from nnik.machine.data import sample_points

    ws = scn.workspace
    return np.concatenate([sample_points(ws, 4096 - 256, "uniform", 12345), ws.boundary(64)])


def lut_float(lut: Lut, p_mm: np.ndarray) -> np.ndarray:
    """The quantised table interpolated in float64 at p (mm), clamped to the domain: what the
    integer model approximates, without its position quantisation."""
    a = _bilinear_basis(np.clip(np.asarray(p_mm, float), lut.lo_um / 1000, lut.hi_um / 1000),
                        lut.lo_um, lut.node_um[0], lut.node_um[1], list(zip(lut.recip, lut.shift)))
    v = lut.offset + lut.table * 2.0 ** -np.array(lut.k)
    return np.stack([a @ v[:, :, o].ravel() for o in range(2)], 1)


def lut_int(lut: Lut, in_um: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The C, bit for bit: (N, 2) int64 micrometres -> (out int64 (N, 2), flags int64 (N,),
    pre float64 (N, 2) = the value before the final rounding, in units)."""
    x = np.asarray(in_um, dtype=np.int64).reshape(-1, 2)
    c = np.clip(x, lut.lo_um, lut.hi_um)
    flags = np.any(c != x, axis=1).astype(np.int64)
    t = c - lut.lo_um
    one = np.int64(1) << FRAC_BITS
    ij, fr = [], []
    for a in range(2):
        pos = (t[:, a] * lut.recip[a]) >> lut.shift[a]
        assert pos.max(initial=0) < 2**32
        i, f = pos >> FRAC_BITS, pos & (one - 1)
        over = i >= lut.ncell[a]
        i = np.where(over, lut.ncell[a] - 1, i)
        f = np.where(over, one, f)
        ij.append(i)
        fr.append(f >> (FRAC_BITS - lut.wbits))
    (ix, iy), (fx, fy) = ij, fr
    w = lut.wbits
    w11 = (fx * fy) >> w
    w10, w01 = fx - w11, fy - w11
    w00 = (np.int64(1) << w) - fx - fy + w11
    out = np.empty_like(c)
    pre = np.empty(c.shape, dtype=np.float64)
    tab = lut.table
    lim = 2**31
    for o in range(2):
        acc = (tab[iy, ix, o] * w00 + tab[iy, ix + 1, o] * w10
               + tab[iy + 1, ix, o] * w01 + tab[iy + 1, ix + 1, o] * w11)
        s = lut.k[o] + w
        assert np.abs(acc).max(initial=0) + (1 << max(s - 1, 0)) < lim
        r = ((acc + (np.int64(1) << (s - 1))) >> s) if s > 0 else acc
        out[:, o] = lut.offset[o] + r
        pre[:, o] = lut.offset[o] + acc / 2.0**s
    if lut.code_range is not None:
        out = np.clip(out, *lut.code_range)
    return out, flags, pre


def render_lut_c(lut: Lut, name: str | None = None) -> dict[str, str]:
    """C99 sources {"NAME_lut.h": ..., "NAME_lut.c": ...}; needs codegen/runtime/nnik_flash.h."""
    name = _check_name(name or lut.scenario)
    if lut.table.size > MAX_ENTRIES:
        raise NnikError(f"table of {lut.table.size} entries is too large for uint16 indexing")
    ctype = "int16_t" if lut.entry_bits == 16 else "int32_t"
    rows = []
    for iy in range(lut.ny):
        vals = lut.table[iy].reshape(-1)
        rows.append(", ".join(str(int(v)) for v in vals))
    s = [lut.k[o] + lut.wbits for o in range(2)]
    ctx = dict(
        prefix=f"{name}_lut",
        guard=f"NNIK_{name.upper()}_LUT_H",
        lut=lut,
        scenario_text=c_comment_safe(lut.scenario),
        ctype=ctype,
        rd="NNIK_RD_I16" if lut.entry_bits == 16 else "NNIK_RD_I32",
        rows=rows,
        lo=[_i32(v) for v in lut.lo_um],
        hi=[_i32(v) for v in lut.hi_um],
        fb=FRAC_BITS,
        one=1 << FRAC_BITS,
        wshift=FRAC_BITS - lut.wbits,
        wone=1 << lut.wbits,
        s=s,
        half=[_i32(1 << (v - 1)) if v > 0 else None for v in s],
        off=[_i32(v) for v in lut.offset],
        code_range=lut.code_range,
        code_lo=_i32(lut.code_range[0]) if lut.code_range else None,
        code_hi=_i32(lut.code_range[1]) if lut.code_range else None,
        cell_um=[float(lut.node_um[a][1]) for a in range(2)],
    )
    env = environment()
    return {
        f"{name}_lut.h": env.get_template("lut_ik.h.j2").render(**ctx),
        f"{name}_lut.c": env.get_template("lut_ik.c.j2").render(**ctx),
    }


def lut_accuracy(lut: Lut, in_um: np.ndarray, truth: np.ndarray) -> dict:
    """Error of the integer table (rounded outputs and pre-rounding values) against the truth
    (units) at the integer inputs in_um (N, 2)."""
    from nnik.implementations.mlp.evaluate import error_stats

    out, _, pre = lut_int(lut, in_um)
    return {"out": error_stats(out, truth), "pre": error_stats(pre, truth),
            "flash_bytes": lut.flash_bytes, "grid": [lut.nx, lut.ny]}
