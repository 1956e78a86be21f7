"""The integer data path of a model on typical inputs: what the data-dependent costs depend on
(tanh input classes, operand signs, clamp hits)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# typical inputs: a fixed uniform sample of the trained domain (the mean is over these)
TYPICAL_N = 2000
TYPICAL_SEED = 12345


def typical_inputs(im, n: int = TYPICAL_N, seed: int = TYPICAL_SEED) -> np.ndarray:
    """A fixed uniform sample of the trained domain, integer micrometres (the 'typical inputs')."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(im.inp.lo, dtype=np.int64), np.asarray(im.inp.hi, dtype=np.int64)
    return np.stack([rng.integers(lo[j], hi[j] + 1, n) for j in range(len(lo))], 1)


def tanh_classes(variant) -> list[str]:
    """Input classes of a tanh variant whose C takes different paths: region/segment x sign."""
    from nnik.implementations.mlp import tanh as activations

    v = activations.get_variant(variant)
    if v.kind == "lerp":
        base = [f"r{i}" for i in range(len(v.regions))] + ["sat"]
    elif v.kind == "poly":
        base = (["zero"] if v.pin_zero else []) + [f"s{i}" for i in range(len(v.segments))] + ["sat"]
    else:  # an unknown form: one class
        base = ["all"]
    return [f"{b}{s}" for b in base for s in "+-"]


def tanh_class_index(variant, T: np.ndarray) -> np.ndarray:
    """Index into tanh_classes(variant) for each int16 tanh input T."""
    from nnik.implementations.mlp import tanh as activations

    v = activations.get_variant(variant)
    T = np.asarray(T, dtype=np.int64)
    a = np.abs(T)
    neg = (T < 0).astype(np.int64)
    if v.kind == "lerp":
        b = np.full(a.shape, len(v.regions), dtype=np.int64)  # sat
        for i in reversed(range(len(v.regions))):
            b = np.where(a < v.regions[i]["a_hi"], i, b)
    elif v.kind == "poly":
        off = 1 if v.pin_zero else 0
        nseg = len(v.segments)
        b = np.full(a.shape, off + nseg, dtype=np.int64)  # sat
        inside = a < v.sat_a
        if v.index_shift is not None:
            seg = np.minimum(a >> v.index_shift, nseg - 1)
        else:
            seg = np.full(a.shape, nseg - 1, dtype=np.int64)
            for i in reversed(range(nseg - 1)):
                seg = np.where(a <= v.segments[i]["a_hi"], i, seg)
        b = np.where(inside, off + seg, b)
        if v.pin_zero:
            b = np.where(a == 0, 0, b)
    else:
        b = np.zeros(a.shape, dtype=np.int64)
    return 2 * b + neg


@dataclass
class _Trace:
    d: np.ndarray  # (N, n_in) um offsets
    dk: np.ndarray  # (N, n_in) pre-shifted offsets (the multiply operand of the input stage)
    layers: list  # per hidden layer: (v_in (N, n_prev), T (N, H) after any clamp, clamp hits (N,))
    h: np.ndarray  # (N, H_last) last hidden activations (the output layer's operands)


def _tanh_of(im, L, T):
    """The model's own tanh for layer L (a kernel may use another table than the variant)."""
    fn = getattr(im, "_tanh", None)
    if fn is not None:
        return np.asarray(fn(L, T), dtype=np.int64)
    from nnik.implementations.mlp import tanh as activations

    return activations.tanh_int(T, im.tanh_variant).astype(np.int64)


def hidden_trace(im, in_um: np.ndarray) -> _Trace:
    """The integer data path (as nnik.implementations.mlp.fixedpoint.IntegerModel computes it), keeping what the
    cost depends on: operand signs, tanh inputs, clamp hits."""
    from nnik.machine.domain import round_half_up_shift
    from nnik.implementations.mlp.fixedpoint import I16_MAX, clamp_um_from, round_half_up_shift_vec

    in_um = np.asarray(in_um, dtype=np.int64)
    x_c, _ = clamp_um_from(in_um, im.inp.lo, im.inp.hi)
    d = x_c - im.inp.mid
    dk = round_half_up_shift_vec(d, im.inp.K)
    v = round_half_up_shift_vec(dk * im.inp.M, im.inp.S)
    layers = []
    for L in im.hidden:
        acc = v @ np.asarray(L.W, dtype=np.int64).T + np.asarray(L.B, dtype=np.int64)
        T = round_half_up_shift(acc, L.sh)
        hits = np.zeros(len(T), dtype=np.int64)
        if L.saturate:
            hits = np.count_nonzero(np.abs(T) > I16_MAX, axis=1)
            T = np.clip(T, -I16_MAX, I16_MAX)
        layers.append((v, T, hits))
        v = _tanh_of(im, L, T)
    return _Trace(d, dk, layers, v)


def sign_counts(W: np.ndarray, v: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Over the MACs of a layer (weights W (out, in), operands v (N, in)): negative weights
    (constant), negative operands (N,), both negative (N,)."""
    negw = (np.asarray(W) < 0)
    negv = (v < 0)
    return float(negw.sum()), negv.sum(1) * W.shape[0], negv.astype(np.int64) @ negw.sum(0)


def dac_hits(im, in_um: np.ndarray) -> np.ndarray:
    from nnik.machine.domain import round_half_up_shift

    o = im.out
    if o.code_range is None:
        return np.zeros(len(in_um), dtype=np.int64)
    total, _, _ = im.run(in_um)
    r = round_half_up_shift(total, o.F)
    return np.count_nonzero((r < o.code_range[0]) | (r > o.code_range[1]), axis=1)
