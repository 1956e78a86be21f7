"""The "fast" MLP kernel: its tanh table and the choice of its fixed-point formats.

``quantize(..., kernel="fast")`` selects it (``render_model_c`` follows the model).  It
computes exactly what :class:`nnik.implementations.mlp.fixedpoint.IntegerModel` says (the Python model stays the
oracle), but its formats are chosen so that an 8-bit CPU does little besides multiplying:

* layer 1 takes the micrometre offsets pre-shifted to int16 (``u = (d + 2^(K-1)) >> K``)
  directly; the input normalisation is folded into the layer-1 weights (no input multiply);
* every hidden layer's tanh input ``T = acc >> sh`` is in Q(m).(15-m) (``m`` integer bits,
  0..3, the fewest the worst-case integer bound allows), and ``sh`` is 16 wherever that costs
  at most one bit of ``T`` resolution and keeps the table within budget, so ``T`` is the top
  half of the int32 accumulator;
* tanh is a uniform table over the whole int16 range of ``T`` (offset binary, no |x| and no
  sign restore), interpolated linearly: node ``Tu >> s`` (``Tu = T + 32768``; ``s = 8``:
  the node index is the top byte of ``Tu``, the fraction its low byte), one 16x8 multiply;
* the products are exact int16 x int16 -> int32 (the C fast paths use offset-binary
  operands, ``x + 32768``, with the ``-32768 * sum(w)`` term folded into the bias; the sums
  are the same integers);
* residual models prefer an affine base floor(d A / 2^16) (a byte-aligned 48-bit product).

The C: nnik.implementations.mlp.fastc (portable C99 body) with nnik.implementations.mlp.fastc_avr (one avr-gcc asm statement) and
nnik.implementations.mlp.fastc_p18 (one SDCC pic16 __asm__), on the primitives of codegen/runtime/nnik_kernel.h.

Table contract (``ulerp``): input T int16 in Q(15-m) (x = T / 2^(15-m)); ``Tu = T + 32768``
(uint16), ``i = Tu >> s``, ``f = (Tu & (2^s - 1)) << (8 - s)`` (8-bit fraction);
``hu = Y[i] + (((Y[i+1] - Y[i]) * f + 128) >> 8)`` with ``Y`` the 2^(16-s) + 1 nodes in offset
binary (Q15 + 32768, non-decreasing, in [1, 65535]); ``h = hu - 32768`` in Q15, |h| <= 32767.
Not exactly odd (the rounding of the interpolation is half-up on both sides of 0).
"""

from __future__ import annotations

import functools

import numpy as np

from nnik.errors import NnikError

KERNELS = ("portable", "fast")
DEFAULT_KERNEL = "portable"
# the fast tanh may use a coarser table (fewer bits of T, a byte-aligned T) while its error
# stays within this budget (LSB of Q15, over every int16 input): the default portable
# variant's own budget (activations.choose_variant(2.0))
FAST_TANH_BUDGET_LSB = 2.0
Y_MAX = 32767


def check_kernel(kernel: str | None) -> str:
    k = DEFAULT_KERNEL if kernel is None else str(kernel)
    if k not in KERNELS:
        raise NnikError(f"unknown kernel {k!r}; choose one of {', '.join(KERNELS)}")
    return k


def ulerp_name(m: int, s: int) -> str:
    """Name of a fast tanh table: input Q(m).(15-m), node step 2^s."""
    return f"ulerp_q{m}.{15 - m}_s{s}"


@functools.cache
def _ulerp_table_cached(m: int, s: int) -> tuple[int, ...]:
    return tuple(int(v) for v in _fit_ulerp(m, s))


def ulerp_table(m: int, s: int) -> np.ndarray:
    """The 2^(16-s) + 1 offset-binary uint16 nodes (as int64) of the fast tanh for Q(m).(15-m)."""
    if not (0 <= m <= 3 and 4 <= s <= 8):
        raise NnikError(f"fast tanh: unsupported format m={m}, s={s}")
    return np.array(_ulerp_table_cached(m, s), dtype=np.int64)


def ulerp_eval(T: np.ndarray, table: np.ndarray, s: int) -> np.ndarray:
    """Bit-exact model of the C: int16 T -> int64 h in Q15."""
    Tu = np.asarray(T, dtype=np.int64) + 32768
    if Tu.size and (Tu.min() < 0 or Tu.max() > 65535):
        raise NnikError("fast tanh: input outside int16")
    i = Tu >> s
    f = (Tu & ((1 << s) - 1)) << (8 - s)
    y0 = table[i]
    d = table[i + 1] - y0
    return y0 + ((d * f + 128) >> 8) - 32768


def _exact(m: int) -> np.ndarray:
    T = np.arange(-32768, 32768, dtype=np.int64)
    return np.tanh(T / float(1 << (15 - m))) * 32768.0


def _fit_ulerp(m: int, s: int) -> np.ndarray:
    """Near-minimax nodes (chord sag split between the nodes), then integer tuning of the
    max and summed-square error of the two segments each node touches."""
    n = 1 << (16 - s)
    idx = np.arange(n + 1)
    x = (idx * (1 << s) - 32768) / float(1 << (15 - m))
    sag = np.zeros(n)
    for k in range(n):
        xs = np.linspace(x[k], x[k + 1], 33)
        e = np.tanh(xs) - np.interp(xs, x[k:k + 2], np.tanh(x[k:k + 2]))
        sag[k] = e[np.argmax(np.abs(e))]
    lift = np.zeros(n + 1)
    lift[1:-1] = (sag[:-1] + sag[1:]) / 4
    lift[0], lift[-1] = sag[0] / 2, sag[-1] / 2
    Y = np.clip(np.rint((np.tanh(x) + lift) * 32768), -Y_MAX, Y_MAX).astype(np.int64) + 32768
    Y = np.maximum.accumulate(Y)
    return _tune(Y, m, s)


def _tune(Y: np.ndarray, m: int, s: int, rounds: int = 12) -> np.ndarray:
    ex = _exact(m)
    T = np.arange(-32768, 32768, dtype=np.int64)
    seg = (T + 32768) >> s
    n = Y.size - 1

    def scores(tab):
        e = np.abs(ulerp_eval(T, tab, s) - ex)
        mx = np.zeros(n)
        np.maximum.at(mx, seg, e)
        ss = np.bincount(seg, weights=e * e, minlength=n)
        pm, ps = np.r_[0.0, mx, 0.0], np.r_[0.0, ss, 0.0]
        return np.maximum(pm[:-1], pm[1:]) * 1e6 + ps[:-1] + ps[1:]  # per node

    idx = np.arange(Y.size)
    for _ in range(rounds):
        changed = False
        for parity in (0, 1):
            sel = idx % 2 == parity
            best = scores(Y)
            bestY = Y.copy()
            for delta in (-1, 1):
                c = np.clip(Y + np.where(sel, delta, 0), 1, 65535)
                ok = sel & np.r_[True, c[1:] >= Y[:-1]] & np.r_[c[:-1] <= Y[1:], True]
                c = np.where(ok, c, Y)
                sc = scores(c)
                better = ok & (sc < best - 1e-9)
                bestY[better] = c[better]
                best = np.where(better, sc, best)
            if (bestY != Y).any():
                Y, changed = bestY, True
        if not changed:
            break
    return Y


@functools.cache
def ulerp_stats(m: int, s: int) -> dict:
    """Integer error of a fast tanh table over all 65536 inputs, LSB of Q15."""
    tab = ulerp_table(m, s)
    T = np.arange(-32768, 32768, dtype=np.int64)
    e = ulerp_eval(T, tab, s) - _exact(m)
    return {"name": ulerp_name(m, s), "max_lsb": float(np.abs(e).max()),
            "rms_lsb": float(np.sqrt(np.mean(e * e))), "table_bytes": int(2 * tab.size),
            "monotone": bool((np.diff(tab) >= 0).all()), "in_frac": 15 - m, "step_shift": s}


def choose_tanh_format(sh_of_m, m_min: int, budget_lsb: float = FAST_TANH_BUDGET_LSB) -> tuple[int, int]:
    """(m, s) for a layer whose tanh input needs at least m_min integer bits.

    sh_of_m(m) is the accumulator shift that format implies.  A byte-aligned shift (16) is
    taken when it needs at most one more integer bit and its table is within the budget;
    otherwise the finest format, with the coarsest node step (8, 7, 6, ...) within budget.
    """
    for m in range(m_min, min(m_min + 1, 3) + 1):
        if sh_of_m(m) == 16 and ulerp_stats(m, 8)["max_lsb"] <= budget_lsb:
            return m, 8
    for s in (8, 7, 6, 5, 4):
        if ulerp_stats(m_min, s)["max_lsb"] <= budget_lsb:
            return m_min, s
    return m_min, 4
