"""Fitting the tanh replacements: polynomial pieces by least squares or minimax (LP), their
quantisation and tuning against the integer evaluation, and the interpolated tables' nodes
(see :mod:`nnik.implementations.mlp.tanh`)."""

from __future__ import annotations

import math

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.mlp.tanh_eval import _lerp_int_eval, _poly_int_eval, _poly_seg_eval, exact_q15
from nnik.implementations.mlp.tanh_spec import (
    _x_to_a, A_MAX, LerpSpec, ONE_OUT, PolySpec, Q_IN, Q_OUT, Variant, Y_MAX)


# --------------------------------------------------------------------------------------
# polynomial fitting (float)
# --------------------------------------------------------------------------------------


def _poly_segments(spec: PolySpec) -> tuple[list[dict], int, float]:
    """Integer domains of the segments: a_lo..a_hi inclusive, origin org (t = (a-org)/4096)."""
    segs = []
    if spec.breaks is not None:
        br = spec.breaks
        if br[0] != 0.0 or any(b1 <= b0 for b0, b1 in zip(br, br[1:])):
            raise NnikError(f"{spec.name}: breakpoints must start at 0 and increase")
        a_lo = 0
        for j in range(len(br) - 1):
            a_hi = int(math.floor(_x_to_a(br[j + 1])))
            org = int(round(_x_to_a(br[j])))
            org = min(org, a_lo)
            segs.append(dict(a_lo=a_lo, a_hi=a_hi, org=org, x_lo=br[j], x_hi=br[j + 1]))
            a_lo = a_hi + 1
        sat_a = a_lo
        sat_x = br[-1]
    else:
        k, n = spec.shift, spec.nseg
        w = 1 << k
        for j in range(n):
            segs.append(dict(a_lo=j * w, a_hi=(j + 1) * w - 1, org=j * w,
                             x_lo=j * w / 4096.0, x_hi=(j + 1) * w / 4096.0))
        sat_a = n * w
        sat_x = sat_a / 4096.0
    if sat_a > A_MAX:
        raise NnikError(f"{spec.name}: saturation beyond |x| = 8")
    for sg in segs:
        tmax = sg["a_hi"] - sg["org"]
        s = 0
        while (tmax << (s + 1)) <= 32767:
            s += 1
        if tmax > 32767:
            raise NnikError(f"{spec.name}: segment wider than 8")
        sg["s"] = s
        sg["x0"] = sg["org"] / 4096.0
        sg["w"] = max(tmax, 1) / 4096.0
    return segs, sat_a, sat_x


def _degrees(spec: PolySpec, n: int) -> list[int]:
    d = spec.degree
    degs = [d] * n if isinstance(d, int) else list(d)
    if len(degs) != n:
        raise NnikError(f"{spec.name}: {len(degs)} degrees for {n} segments")
    return degs


_LP_POINTS = 256


def _fit_poly_float(spec: PolySpec, segs: list[dict]) -> list[np.ndarray]:
    """Coefficients ascending in t = x - x0 for each segment (float64)."""
    degs = _degrees(spec, len(segs))
    # design blocks in tau = t / w (well conditioned), on every Q3.12 point of the segment
    blocks, targets = [], []
    for sg, d in zip(segs, degs):
        a = np.arange(sg["a_lo"], sg["a_hi"] + 1, dtype=np.float64)
        if spec.method == "minimax" and a.size > _LP_POINTS:
            # LP grid: uniform plus Chebyshev points (dense near the ends, where the
            # extrema of a minimax error crowd); the integer tuning works on every point


            n = _LP_POINTS // 2
            cheb = (1 - np.cos(np.linspace(0, np.pi, n))) / 2
            idx = np.unique(np.r_[np.linspace(0, 1, n), cheb] * (a.size - 1)).round()
            a = a[np.unique(idx.astype(int))]
        x = a / 4096.0
        tau = (x - sg["x0"]) / sg["w"]
        blocks.append(np.vander(tau, d + 1, increasing=True))
        targets.append(np.tanh(x))
    ncoef = [d + 1 for d in degs]
    offs = np.r_[0, np.cumsum(ncoef)]
    nvar = int(offs[-1])

    # continuity rows: p_j(x_{j+1}) = p_{j+1}(x_{j+1}); last: p_n(sat_x) = 1
    eq_rows, eq_rhs = [], []
    if spec.continuous:
        for j, (sg, d) in enumerate(zip(segs, degs)):
            xb = sg["x_hi"]
            row = np.zeros(nvar)
            row[offs[j]:offs[j + 1]] = ((xb - sg["x0"]) / sg["w"]) ** np.arange(d + 1)
            if j + 1 < len(segs):
                nx = segs[j + 1]
                row[offs[j + 1]:offs[j + 2]] = -(((xb - nx["x0"]) / nx["w"]) ** np.arange(degs[j + 1] + 1))
                eq_rhs.append(0.0)
            else:
                eq_rhs.append(1.0)
            eq_rows.append(row)
    if spec.origin_zero:  # p(0) = 0, so that the integer form is odd at v = 0 as well
        row = np.zeros(nvar)
        row[offs[0]:offs[1]] = ((0.0 - segs[0]["x0"]) / segs[0]["w"]) ** np.arange(degs[0] + 1)
        eq_rows.append(row)
        eq_rhs.append(0.0)

    if spec.method == "lsq":
        # normal equations are block diagonal (one block per segment)
        G = np.zeros((nvar, nvar))
        g = np.zeros(nvar)
        for j, (b, t) in enumerate(zip(blocks, targets)):
            sl = slice(offs[j], offs[j + 1])
            G[sl, sl] = b.T @ b
            g[sl] = b.T @ t
        if eq_rows:
            E = np.array(eq_rows)
            K = np.block([[G, E.T], [E, np.zeros((len(eq_rows), len(eq_rows)))]])
            sol = np.linalg.solve(K, np.r_[g, eq_rhs])[:nvar]
        else:
            sol = np.zeros(nvar)
            for j, (b, t) in enumerate(zip(blocks, targets)):
                sol[offs[j]:offs[j + 1]] = np.linalg.lstsq(b, t, rcond=None)[0]
    elif spec.method == "minimax":
        from scipy.optimize import linprog

        # one LP per segment (or one joint LP when continuity couples them)
        def solve(block_ids):
            cols = np.r_[tuple(np.arange(offs[j], offs[j + 1]) for j in block_ids)]
            nv = cols.size
            rows, rhs = [], []
            for j in block_ids:
                b = blocks[j]
                full = np.zeros((b.shape[0], nv))
                c0 = int(np.searchsorted(cols, offs[j]))
                full[:, c0:c0 + b.shape[1]] = b
                rows.append(np.c_[full, -np.ones(b.shape[0])])
                rhs.append(targets[j])
                rows.append(np.c_[-full, -np.ones(b.shape[0])])
                rhs.append(-targets[j])
            A_ub = np.vstack(rows)
            b_ub = np.concatenate(rhs)
            cobj = np.zeros(nv + 1)
            cobj[-1] = 1.0
            A_eq = b_eq = None
            if eq_rows:
                E = np.array(eq_rows)
                outside = np.ones(nvar, dtype=bool)
                outside[cols] = False
                keep = ~(E[:, outside] != 0).any(axis=1) & (E[:, cols] != 0).any(axis=1)
                if keep.any():
                    A_eq = np.c_[E[keep][:, cols], np.zeros(int(keep.sum()))]
                    b_eq = np.array(eq_rhs)[keep]
            res = linprog(cobj, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq,
                          bounds=[(None, None)] * (nv + 1), method="highs")
            if res.status != 0:
                raise NnikError(f"{spec.name}: minimax LP failed: {res.message}")
            return cols, res.x[:nv]

        sol = np.zeros(nvar)
        groups = ([list(range(len(segs)))] if spec.continuous
                  else [[j] for j in range(len(segs))])
        for g in groups:
            cols, xs = solve(g)
            sol[cols] = xs
    else:
        raise NnikError(f"{spec.name}: unknown method {spec.method!r}")

    coeffs = []
    for j, (sg, d) in enumerate(zip(segs, degs)):
        b = sol[offs[j]:offs[j + 1]]
        coeffs.append(b / sg["w"] ** np.arange(d + 1))  # tau -> t
    return coeffs


def _eval_pieces(v: Variant, x: np.ndarray) -> np.ndarray:
    """Float evaluation of the unquantised pieces on |x| >= 0 (sign restored)."""
    x = np.asarray(x, dtype=np.float64)
    ax = np.abs(x)
    y = np.ones_like(ax)
    if v.kind == "poly":
        for sg, (x_lo, x_hi, x0, c) in zip(v.segments, v.pieces):
            if v.index_shift is None:  # [0,x1], (x1,x2], ...
                m = (ax <= x_hi) & ((ax > x_lo) | (x_lo == 0.0))
            else:  # [lo, hi)
                m = (ax >= x_lo) & (ax < x_hi)
            y[m] = np.polynomial.polynomial.polyval(ax[m] - x0, c)
    else:
        xn, yn = v.float_nodes[:, 0], v.float_nodes[:, 1]
        m = ax < v.sat_x
        y[m] = np.interp(ax[m], xn, yn)
    return np.where(x < 0, -y, y)

def _tune_poly(v: Variant) -> None:
    """Integer-aware minimax: coordinate descent on each segment's int16 coefficients
    (steps 16, 4, 1), minimising (max error, then summed square error) of the exact
    integer evaluation on every Q3.12 point of the segment.  (Monotonicity is not
    enforced: the rounding of the Horner steps can make 1-LSB dips where tanh is flat.)"""
    for j, sg in enumerate(v.segments):
        a = np.arange(sg["a_lo"], sg["a_hi"] + 1, dtype=np.int64)
        u = (a - sg["org"]) << sg["s"]
        ex = exact_q15(a)
        sh = v.sh[j]

        def score(c):
            try:
                r = np.clip(_poly_seg_eval(c, sh, u, check=True), 0, Y_MAX)
            except OverflowError:
                return None
            e = r - ex
            return (round(float(np.abs(e).max()), 9), float(np.dot(e, e)))

        c = v.coef[j].copy()
        frozen = {c.size - 1} if (j == 0 and v.origin_zero) else set()
        best = score(c)
        if best is None:
            raise NnikError(f"{v.name}: Horner overflow in segment {j}")
        for step in (16, 4, 1):
            for _ in range(40):
                improved = False
                for i in range(c.size):
                    if i in frozen:
                        continue
                    for d in (step, -step):
                        cand = c.copy()
                        cand[i] += d
                        if abs(cand[i]) > 32767:
                            continue
                        sc = score(cand)
                        if sc is not None and sc < best:
                            c, best, improved = cand, sc, True
                if not improved:
                    break
        v.coef[j] = c


def _quantise_poly(v: Variant, coeffs: list[np.ndarray], uniform_q: bool) -> None:
    deg = v.degree
    nseg = len(coeffs)
    # Horner partial sums h_i(t) = sum_{k>=i} c_k t^(k-i); magnitudes on the segment grid
    C = np.zeros((nseg, deg + 1))  # ascending, padded
    for j, c in enumerate(coeffs):
        C[j, :c.size] = c
    M = np.zeros((nseg, deg + 1))
    for j, sg in enumerate(v.segments):
        t = (np.arange(sg["a_lo"], sg["a_hi"] + 1) - sg["org"]) / 4096.0
        h = np.zeros_like(t)
        for i in range(deg, -1, -1):
            h = C[j, i] + t * h
            M[j, i] = max(np.abs(h).max(), abs(C[j, i]))
    lim = 32767.0  # the exhaustive overflow check below backs this off where needed
    with np.errstate(divide="ignore"):
        qf = np.floor(np.log2(lim / M))
    qf[~np.isfinite(qf)] = 30
    qf = np.minimum(qf, 30).astype(np.int64)
    qf[:, 0] = Q_OUT
    if uniform_q:
        qf[:, 1:] = qf[:, 1:].min(axis=0)
    for _ in range(64):  # shrink Q formats until the exact integer model has no overflow
        s = np.array([sg["s"] for sg in v.segments])
        # step i computes h_{deg-1-i} from h_{deg-i}: shift = q_hi + 12 + s - q_lo >= 1
        for i in range(deg - 1, 0, -1):
            qf[:, i] = np.minimum(qf[:, i], qf[:, i + 1] + Q_IN + s - 1)
        sh = np.zeros((nseg, deg), dtype=np.int64)
        for i in range(deg):
            hi_q = qf[:, deg - i]
            lo_q = qf[:, deg - i - 1]
            sh[:, i] = hi_q + Q_IN + s - lo_q
        if (sh < 1).any():
            raise NnikError(f"{v.name}: cannot build a fixed-point Horner scheme")
        if (sh > 30).any():  # keeps 2^(sh-1) and p + 2^(sh-1) inside int32
            raise NnikError(f"{v.name}: a Horner shift exceeds 30")
        coef = np.zeros((nseg, deg + 1), dtype=np.int64)
        for j in range(nseg):
            for i in range(deg + 1):
                coef[j, deg - i] = int(round(C[j, i] * 2.0 ** qf[j, i]))
        if np.abs(coef).max() > 32767:
            bad = np.argwhere(np.abs(coef) > 32767)
            if (bad[:, 1] == deg).any():
                raise NnikError(f"{v.name}: a constant term does not fit Q15")
            for j, i in bad:
                qf[j if not uniform_q else slice(None), deg - i] -= 1
            continue
        v.coef, v.q, v.sh = coef, qf[:, ::-1].copy(), sh
        try:
            _poly_int_eval(v, np.arange(0, A_MAX + 1), check=True)
        except OverflowError as e:
            j, i = e.args[0]
            qf[j if not uniform_q else slice(None), deg - i - 1] -= 1
            continue
        break
    else:
        raise NnikError(f"{v.name}: no overflow-free Q formats found")
    v.uniform_shifts = bool((v.sh == v.sh[0]).all())


def _build_poly(spec: PolySpec) -> Variant:
    segs, sat_a, sat_x = _poly_segments(spec)
    coeffs = _fit_poly_float(spec, segs)
    degs = _degrees(spec, len(segs))
    v = Variant(
        name=spec.name, description=spec.description, kind="poly", method=spec.method,
        sat_x=sat_x, sat_a=sat_a, nseg=len(segs), degree=max(degs),
        continuous=spec.continuous, index_shift=spec.shift, segments=segs,
    )
    v.pieces = [(sg["x_lo"], sg["x_hi"], sg["x0"], c) for sg, c in zip(segs, coeffs)]
    _quantise_poly(v, coeffs, spec.uniform_q)
    v.origin_zero = spec.origin_zero
    if spec.tune:
        _tune_poly(v)
    v.pin_zero = bool(_poly_int_eval(v, np.zeros(1, dtype=np.int64))[0] != 0)
    return v

def _build_lerp(spec: LerpSpec) -> Variant:
    regions, node_a = [], [0]
    for x_lo, x_hi, k in spec.regions:
        a_lo, a_hi = _x_to_a(x_lo), _x_to_a(x_hi)
        w = 1 << k
        if a_lo != int(a_lo) or a_hi != int(a_hi) or int(a_lo) % w or int(a_hi) % w:
            raise NnikError(f"{spec.name}: region [{x_lo},{x_hi}) not on a 2^{k} grid")
        a_lo, a_hi = int(a_lo), int(a_hi)
        if a_lo != node_a[-1] or a_hi <= a_lo:
            raise NnikError(f"{spec.name}: regions must be contiguous from 0")
        if not 1 <= k <= 14:
            raise NnikError(f"{spec.name}: step 2^{k} out of range")
        base = len(node_a) - 1
        # fb: fraction bits used for the interpolation.  Steps wider than 2^8 use only
        # the top 8 bits (an 8-bit multiplier operand, and >> 8 is a byte move); tanh
        # is flat where such steps are used, so the lost bits cost < 0.1 LSB
        regions.append(dict(a_lo=a_lo, a_hi=a_hi, k=k, off=base - (a_lo >> k),
                            fb=min(k, 8), drop=k - min(k, 8)))
        node_a.extend(range(a_lo + w, a_hi + 1, w))
    sat_a = node_a[-1]
    if sat_a > A_MAX:
        raise NnikError(f"{spec.name}: saturation beyond |x| = 8")
    node_a = np.array(node_a, dtype=np.int64)
    xn = node_a / 4096.0

    # near-minimax float nodes: lift each node by half the mean chord sag of its segments
    # (tanh is concave on x > 0, so every chord lies below it)
    sag = np.zeros(node_a.size - 1)
    for s in range(sag.size):
        xs = np.linspace(xn[s], xn[s + 1], 257)
        chord = np.interp(xs, xn[s:s + 2], np.tanh(xn[s:s + 2]))
        sag[s] = (np.tanh(xs) - chord).max()
    lift = np.zeros(node_a.size)
    lift[1:-1] = (sag[:-1] + sag[1:]) / 4
    lift[-1] = sag[-1] / 2
    yn = np.tanh(xn) + lift
    yn[0] = 0.0

    desc = spec.description or (
        "table, step " + ", ".join(
            f"1/{4096 >> k} on [{lo:g},{hi:g})" for lo, hi, k in spec.regions)
        + f" ({node_a.size} nodes), linear interpolation, 1 from {sat_a / 4096:g}")
    v = Variant(
        name=spec.name, description=desc, kind="lerp", method="table",
        sat_x=sat_a / 4096.0, sat_a=sat_a, nseg=node_a.size - 1, degree=1,
        continuous=True, regions=regions,
    )
    v.float_nodes = np.c_[xn, yn]
    v.pieces = [(float(xn[i]), float(xn[i + 1]), float(xn[i]),
                 np.array([yn[i], (yn[i + 1] - yn[i]) / (xn[i + 1] - xn[i])]))
                for i in range(node_a.size - 1)]
    T = np.clip(np.round(yn * ONE_OUT), 0, Y_MAX).astype(np.int64)
    T[0] = 0
    T = np.maximum.accumulate(T)
    if spec.tune:
        T = _tune_table(v, T, node_a)
    v.table = T
    # the C multiplies (uint16)d * f in 16 bits: check it cannot wrap
    for rg in regions:
        n0 = rg["a_lo"] >> rg["k"]
        n1 = rg["a_hi"] >> rg["k"]
        i0, i1 = n0 + rg["off"], n1 + rg["off"]
        dmax = int(np.diff(T[i0:i1 + 1]).max())
        rg["dmax"] = dmax
        rg["mask"] = (1 << rg["k"]) - 1
        fmax = (1 << rg["fb"]) - 1
        rg["half"] = 1 << (rg["fb"] - 1)
        rg["wide"] = dmax * fmax + rg["half"] > 0xFFFF
        # AVR has no barrel shifter and avr-gcc -Os emits a loop for >> 1..6: shift
        # left first (when the bound allows) so that the right shift is 8 (a byte
        # move) or 7; the value is unchanged
        rg["idx_pre"] = _shift_pre(rg["k"], rg["a_hi"] - 1)
        rg["mul_pre"] = 0 if rg["wide"] else _shift_pre(rg["fb"], dmax * fmax + rg["half"])
    return v


def _shift_pre(k: int, bound: int) -> int:
    """Left pre-shift p so that (x << p) >> (k + p) == x >> k for 0 <= x <= bound,
    with k + p in (8, 7) and x << p within 16 bits; 0 if none applies."""
    for target in (8, 7):
        p = target - k
        if p > 0 and (bound << p) <= 0xFFFF:
            return p
    return 0


def _tune_table(v: Variant, T: np.ndarray, node_a: np.ndarray) -> np.ndarray:
    """Integer coordinate descent on the nodes: minimise the max (then summed square)
    integer error of the two segments each node touches; even and odd nodes alternate
    so that the nodes updated together share no segment.  Keeps T[0] = 0, monotone."""
    a = np.arange(0, v.sat_a, dtype=np.int64)
    ex = exact_q15(a)
    starts = node_a[:-1]  # a starts at 0, so node positions index it directly
    idx = np.arange(T.size)

    def seg_scores(tab):
        e = _lerp_int_eval(v, a, tab) - ex
        mx = np.maximum.reduceat(np.abs(e), starts)
        ss = np.add.reduceat(e * e, starts)
        return mx, ss

    def node_score(mx, ss):
        # node i touches segments i-1 and i
        pad_mx = np.r_[0.0, mx, 0.0]
        pad_ss = np.r_[0.0, ss, 0.0]
        return np.maximum(pad_mx[:-1], pad_mx[1:]) * 1e6 + pad_ss[:-1] + pad_ss[1:]

    for _ in range(12):
        changed = False
        for parity in (0, 1):
            sel = (idx % 2 == parity) & (idx > 0)
            mx, ss = seg_scores(T)
            best = node_score(mx, ss)
            bestT = T.copy()
            for delta in (-1, 1):
                cand = T.copy()
                cand[sel] += delta
                ok = sel & (cand >= 0) & (cand <= Y_MAX)
                ok &= np.r_[True, cand[1:] >= T[:-1]] & np.r_[cand[:-1] <= T[1:], True]
                cand = np.where(ok, cand, T)
                cmx, css = seg_scores(cand)
                sc = node_score(cmx, css)
                better = ok & (sc < best - 1e-9)
                bestT[better] = cand[better]
                best = np.where(better, sc, best)
            if (bestT != T).any():
                changed = True
                T = bestT
        if not changed:
            break
    return T
