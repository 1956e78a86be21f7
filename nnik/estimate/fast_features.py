"""Features of the "fast" kernel (nnik.implementations.mlp.kernel, nnik.implementations.mlp.fastc): unrolled, weights as constants in
the code, prefixed by the code path ("asm" or "c") each target takes."""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp import fastc

from nnik.implementations.mlp import fastc_avr

from nnik.implementations.mlp import fastc_p18
from nnik.estimate.structure import structure
from nnik.estimate.trace import dac_hits, hidden_trace, tanh_class_index, tanh_classes

ASM_BODIES = {"avr": fastc_avr, "pic18": fastc_p18}


def fast_path(im, target: str | None) -> str:
    """"asm" when the target's hand-written body applies to the model, else "c" (value code)."""
    mod = ASM_BODIES.get(target or "")
    return "asm" if mod is not None and mod.supported(im) else "c"


def _unroll_max() -> int:
    return int(fastc.UNROLL_MAX_WEIGHTS)


def _tanh_key(im, L) -> str:
    step = int(getattr(L, "tanh_step", 0) or 0)
    return f"ulerp_s{step}" if step else im.tanh_variant


def _weight_classes(W: np.ndarray, looped: bool) -> dict[str, int]:
    """MACs by the code they get: unrolled, by |w| (0 skipped, < 256 an 8-bit multiply);
    looped, by sign (a signed multiply-accumulate)."""
    W = np.asarray(W)
    if looped:
        return {"loop_pos": int(np.count_nonzero(W >= 0)), "loop_neg": int(np.count_nonzero(W < 0))}
    a = np.abs(W)
    return {"u8": int(np.count_nonzero((a > 0) & (a < 256))), "u16": int(np.count_nonzero(a >= 256))}


def _fast_counts(im, target: str | None) -> tuple[str, dict[str, float]]:
    """Constant per-call counts of the fast kernel, prefixed by its code path."""
    s = structure(im)
    path = fast_path(im, target)
    o = im.out
    umax = _unroll_max()
    c: dict[str, float] = {"call": 1.0, "multi_layer": float(s["layers"] > 1), "input_k_bits": float(np.sum(im.inp.K)),
                           "neuron_first": float(s["H"][0]), "neuron_deep": float(s["neurons_deep"])}
    for li, L in enumerate(im.hidden):
        t = "first" if li == 0 else "hidden"
        looped = int(np.asarray(L.W).size) > umax
        for k, n in _weight_classes(L.W, looped).items():
            c[f"mac_{t}_{k}"] = c.get(f"mac_{t}_{k}", 0.0) + n
        if looped:
            c["loop_neuron"] = c.get("loop_neuron", 0.0) + L.W.shape[0]
        H = int(np.asarray(L.W).shape[0])
        sh = int(L.sh)
        key = _tanh_key(im, L)
        c[f"tanh[{key}]"] = c.get(f"tanh[{key}]", 0.0) + H
        c["t_lo_bits"] = c.get("t_lo_bits", 0.0) + H * max(16 - sh, 0)
        c["t_hi_bits"] = c.get("t_hi_bits", 0.0) + H * max(sh - 16, 0)
        c["t_hi"] = c.get("t_hi", 0.0) + H * (sh > 16)
        c["t_lo"] = c.get("t_lo", 0.0) + H * (sh < 16)
        if L.saturate:
            c["sat_clamp"] = c.get("sat_clamp", 0.0) + H
    looped_out = any(int(np.asarray(L.W).size) > umax for L in im.hidden) and bool(
        int(np.asarray(im.hidden[-1].W).size) > umax)
    for k, n in _weight_classes(o.V, looped_out).items():
        c[f"mac_out_{k}"] = n
    e = 15 + int(o.g) - int(o.F)
    fold = e == 0 and not o.residual
    n_out = s["n_out"]
    c["out_fold"] = float(n_out * fold)
    c["out_fold_hi_bits"] = float(n_out * fold * max(int(o.F) - 16, 0))
    c["out_fold_bits"] = float(n_out * fold * int(o.F))
    c["out_e_pos_bits"] = float(n_out * (not fold) * max(e, 0))
    c["out_e_pos"] = float(n_out * (not fold) * (e > 0))
    c["out_e_neg"] = float(n_out * (e < 0))
    c["out_F_bits"] = float(n_out * (not fold) * int(o.F))
    c["out_plain"] = float(n_out * (not fold))
    c["affine_term"] = float(n_out * s["n_in"] if s["residual"] else 0)
    for cl, n in s["affine_mul"].items():
        c[f"affine_mul[{cl}]"] = float(n)
    c["residual"] = float(s["residual"])
    c["dac_clamp"] = float(n_out if s["dac"] else 0)
    c["weights_w8"] = float(s["weight_bits"] == 8)
    return path, {k: v for k, v in c.items() if v != 0 or k == "call"}


def fast_cycle_features(im, in_um: np.ndarray, far: bool, target: str | None) -> dict[str, np.ndarray]:
    path, c = _fast_counts(im, target)
    N = len(in_um)
    one = np.ones(N)
    f = {f"{path}:{k}": v * one for k, v in c.items()}
    if far:
        f[f"{path}:far_neuron"] = float(sum(structure(im)["H"])) * one
    tr = hidden_trace(im, in_um)
    sat = np.zeros(N)
    for li, (v_in, T, hits) in enumerate(tr.layers):
        sat += hits
        L = im.hidden[li]
        if not getattr(L, "tanh_step", 0):  # a portable variant inside the fast kernel: its classes
            V = im.tanh_variant
            idx = tanh_class_index(V, T)
            for ci, name in enumerate(tanh_classes(V)):
                if ci:
                    f[f"{path}:tanh_class[{V}][{name}]"] = f.get(f"{path}:tanh_class[{V}][{name}]", 0) + \
                        np.count_nonzero(idx == ci, axis=1).astype(float)
    if sat.any():
        f[f"{path}:sat_hit"] = sat
    dh = dac_hits(im, in_um).astype(float)
    if dh.any():
        f[f"{path}:dac_hit"] = dh
    return {k: np.broadcast_to(np.asarray(v, dtype=float), (N,)) for k, v in f.items()}


def fast_size_features(im, far: bool, target: str | None) -> dict[str, float]:
    path, c = _fast_counts(im, target)
    s = structure(im)
    f = {f"{path}:{k}": v for k, v in c.items()}
    # unrolled MACs are code; looped layers keep int16 weights and int32 start values in flash
    umax = _unroll_max()
    tb = 0
    for L in im.hidden:
        if int(np.asarray(L.W).size) > umax:
            tb += 2 * int(np.asarray(L.W).size) + 4 * int(np.asarray(L.W).shape[0])
    f[f"{path}:table_bytes"] = float(tb)
    f[f"{path}:tanh_table"] = float(_fast_tanh_bytes(im))
    f[f"{path}:widest"] = float(s["widest"])
    if far:
        f[f"{path}:far_frame"] = 1.0
    return {k: v for k, v in f.items() if v != 0 or k.endswith(":call")}


def _fast_tanh_bytes(im) -> int:
    fn = getattr(im, "tanh_bytes", None)
    if fn is not None:
        try:
            return int(fn())
        except Exception:  # noqa: BLE001 - a model without tables
            return 0
    return 0
