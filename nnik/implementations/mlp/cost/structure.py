"""Constant (per call, per program) counts of a model's network."""

from __future__ import annotations

import itertools

import numpy as np


def structure(im) -> dict:
    """Constant (per call / per program) counts of a model."""
    H = [int(np.asarray(L.W).shape[0]) for L in im.hidden]
    n_in = int(np.asarray(im.hidden[0].W).shape[1])
    o = im.out
    n_out = int(np.asarray(o.V).shape[0])
    e = 15 + int(o.g) - int(o.F)
    wb = int(im.weight_bits)
    w8 = wb == 8
    mac_first = n_in * H[0]
    mac_hidden = sum(a * b for a, b in itertools.pairwise(H))
    mac_out = n_out * H[-1]
    table_bytes = 0
    for L in im.hidden:
        table_bytes += int(np.asarray(L.W).size) * (1 if w8 else 2) + int(np.asarray(L.B).size) * 4
    table_bytes += int(np.asarray(o.V).size) * (1 if w8 else 2)
    return {
        "H": H, "n_in": n_in, "n_out": n_out, "layers": len(H), "e": e, "weight_bits": wb,
        "variant": im.tanh_variant, "residual": bool(o.residual), "dac": o.code_range is not None,
        "k0": int(np.count_nonzero(np.asarray(im.inp.K) == 0)),
        "mac_first": mac_first, "mac_hidden": mac_hidden, "mac_out": mac_out,
        "neurons": sum(H), "neurons_deep": sum(H[1:]), "widest": max(max(H), n_in),
        "sat_neurons": sum(h for h, L in zip(H, im.hidden) if L.saturate),
        "sat_layers": sum(1 for L in im.hidden if L.saturate),
        "table_bytes": table_bytes,
        "affine_mul": _affine_mul_classes(o),
    }


def _const_class(c: int) -> str:
    """How a compiler multiplies an int32 by the constant c: folded (0, 1), unsigned or
    negative 16-bit operand, or a full 32-bit multiply."""
    if c == 0:
        return "zero"
    if c == 1:
        return "one"
    if 0 < c <= 0xFFFF:
        return "u16"
    if -0x10000 <= c < 0:
        return "n16"
    return "s32"


def _affine_mul_classes(o) -> dict[str, int]:
    """Multiplies by constants in the residual affine terms, counted by constant class."""
    out: dict[str, int] = {}
    if not o.residual:
        return out
    for A in (np.asarray(o.A1), np.asarray(o.A0)):
        for c in A.ravel().tolist():
            k = _const_class(int(c))
            out[k] = out.get(k, 0) + 1
    return out
