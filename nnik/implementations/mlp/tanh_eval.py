"""The integer evaluation of a tanh variant, as its C does it: the piecewise polynomials' Horner
steps and the interpolated tables (see :mod:`nnik.implementations.mlp.tanh` for the contract)."""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp.tanh_spec import ONE_OUT, Q_IN, Variant, Y_MAX


# --------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------


def exact_q15(v: np.ndarray) -> np.ndarray:
    """tanh(v/4096) * 32768 in float64 (the reference the integer error is measured to)."""
    return np.tanh(np.asarray(v, dtype=np.float64) / (1 << Q_IN)) * ONE_OUT


def _rshift_round(p: np.ndarray, sh) -> np.ndarray:
    """(p + 2^(sh-1)) >> sh with arithmetic shift (sh >= 1), as the C does on int32."""
    sh = np.asarray(sh, dtype=np.int64)
    return (p + (np.int64(1) << (sh - 1))) >> sh


def _all_inputs() -> np.ndarray:
    return np.arange(-32768, 32768, dtype=np.int64)

# --------------------------------------------------------------------------------------
# polynomial: integer realisation and model
# --------------------------------------------------------------------------------------


def _poly_seg_eval(coef: np.ndarray, sh: np.ndarray, u: np.ndarray, check: bool = False) -> np.ndarray:
    """Fixed-point Horner of one segment on u = (|v| - org) << s, before the final clamp."""
    deg = sh.size
    h = np.full(u.shape, coef[0], dtype=np.int64)
    for i in range(deg):
        t = _rshift_round(h * u, sh[i])
        h = coef[i + 1] + t  # int16 (last step: int32 accumulator)
        if check and i < deg - 1 and u.size and (
                np.abs(t).max() > 32767 or h.max() > 32767 or h.min() < -32768):
            raise OverflowError(i)
    return h


def _poly_int_eval(v: Variant, a: np.ndarray, check: bool = False) -> np.ndarray:
    """Q15 result for |v| = a (int64, 0..32768), emulating the C; optional overflow check."""
    a = np.asarray(a, dtype=np.int64)
    out = np.full(a.shape, Y_MAX, dtype=np.int64)
    for j, sg in enumerate(v.segments):
        m = (a >= sg["a_lo"]) & (a <= sg["a_hi"])
        if not m.any():
            continue
        u = (a[m] - sg["org"]) << sg["s"]
        try:
            h = _poly_seg_eval(v.coef[j], v.sh[j], u, check)
        except OverflowError as e:
            raise OverflowError((j, e.args[0])) from None
        out[m] = np.clip(h, 0, Y_MAX)
    return out

# --------------------------------------------------------------------------------------
# interpolated tables
# --------------------------------------------------------------------------------------


def _lerp_int_eval(v: Variant, a: np.ndarray, table: np.ndarray | None = None) -> np.ndarray:
    a = np.asarray(a, dtype=np.int64)
    T = v.table if table is None else table
    out = np.full(a.shape, Y_MAX, dtype=np.int64)
    for rg in v.regions:
        m = (a >= rg["a_lo"]) & (a < rg["a_hi"])
        if not m.any():
            continue
        am = a[m]
        k, fb = rg["k"], rg["fb"]
        i = (am >> k) + rg["off"]
        f = (am & ((1 << k) - 1)) >> (k - fb)  # the top fb (<= 8) bits of the fraction
        y0 = T[i]


        d = T[i + 1] - y0
        out[m] = y0 + ((d * f + (1 << (fb - 1))) >> fb)
    return out
