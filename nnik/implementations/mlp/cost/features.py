"""Cycle, flash, RAM and stack-frame features of a model (the portable kernel here, the fast
kernel in fast_features)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from nnik.implementations.mlp.cost.fast_features import fast_cycle_features, fast_size_features
from nnik.implementations.mlp.cost.structure import structure
from nnik.implementations.mlp.cost.trace import dac_hits, hidden_trace, sign_counts, tanh_class_index, tanh_classes


def cycle_features(im, in_um: np.ndarray, far: bool = False, target: str | None = None) -> dict[str, np.ndarray]:
    """Per-vector cycle features (name -> (N,) array) of the model's kernel.

    far: the function's stack frame is larger than an AVR Y+q displacement reaches (63), so
    the locals placed above the arrays cost an extra pointer adjustment per access."""
    if getattr(im, "kernel", None) == "fast":
        return fast_cycle_features(im, in_um, far, target)
    return _portable_cycle_features(im, in_um, far)


def _portable_cycle_features(im, in_um: np.ndarray, far: bool = False) -> dict[str, np.ndarray]:
    """Features of the portable C kernel (codegen/templates/model.c.j2)."""
    s = structure(im)
    N = len(in_um)
    V = s["variant"]
    w8 = s["weight_bits"] == 8
    one = np.ones(N)
    f: dict[str, np.ndarray] = {
        "call": one,
        "input_k0": s["k0"] * one,
        # layer 1 always has n_in = 2 operands per neuron: its MACs are part of the neuron cost
        # (tanh[V]); int8 weights (a byte read, sign-extended) add a per-MAC difference
        "mac_hidden": s["mac_hidden"] * one,
        # SDCC indexes a weight table of fewer than 128 bytes with an 8-bit multiply hoisted out
        # of the inner loop, a larger one with a 16-bit multiply call per MAC
        "mac_hidden_bigtab": float(sum(int(np.asarray(L.W).size) for L in im.hidden[1:]
                                       if int(np.asarray(L.W).size) * (1 if w8 else 2) >= 128)) * one,
        "mac_first_w8": (s["mac_first"] if w8 else 0) * one,
        "mac_hidden_w8": (s["mac_hidden"] if w8 else 0) * one,
        "mac_out_w8": (s["mac_out"] if w8 else 0) * one,
        "neuron_deep": s["neurons_deep"] * one,
        "multi_layer": float(s["layers"] > 1) * one,
        "output": s["n_out"] * one,
        "output_e_pos": s["n_out"] * float(s["e"] > 0) * one,
        "output_e_neg": s["n_out"] * float(s["e"] < 0) * one,
        "affine_term": (s["n_out"] * s["n_in"] if s["residual"] else 0) * one,
        "residual": float(s["residual"]) * one,
        **{f"affine_mul[{c}]": n * one for c, n in s["affine_mul"].items()},
        # the affine base keeps d[] live through the hidden layers: more register pressure there
        "residual_neuron": (s["neurons"] if s["residual"] else 0) * one,
        "residual_neuron_deep": (s["neurons_deep"] if s["residual"] else 0) * one,
        "dac_clamp": (s["n_out"] if s["dac"] else 0) * one,
        "sat_clamp": s["sat_neurons"] * one,
        # a frame beyond Y+63: each far local costs an adiw/sbiw pair.  Near and far networks of
        # the same shape cannot both be built outside the judged sizes, so the penalty is modelled
        # as one cost per hidden neuron (it only has to split between layers when H1 != H2)
        "far_neuron": float(far) * s["neurons"] * one,
        "far_residual_neuron": float(far and s["residual"]) * s["neurons"] * one,
        f"tanh[{V}]": s["neurons"] * one,
        **{f"tanh_dead[{V}][{b}]": s["neurons"] * one for b in _dead_tanh_regions(im)},
        f"tanh_call[{V}]": (s["neurons"] if s["layers"] > 1 else 0) * one,
    }
    classes = tanh_classes(V)
    counts = np.zeros((N, len(classes)))
    sat_hits = np.zeros(N)
    tr = hidden_trace(im, in_um)
    # operand signs: the int16 x int16 -> int32 multiply routines correct for negative operands
    sfx = ""
    for li, (v_in, T, hits) in enumerate(tr.layers):
        t = "first" if li == 0 else "hidden"
        nw, nx, nwx = sign_counts(im.hidden[li].W, v_in)
        for key, val in ((f"mac_{t}{sfx}_negw", nw), (f"mac_{t}{sfx}_negx", nx), (f"mac_{t}{sfx}_negwx", nwx)):
            f[key] = f.get(key, 0) + val * one
    nw, nx, nwx = sign_counts(im.out.V, tr.h)
    f[f"mac_out{sfx}_negw"], f[f"mac_out{sfx}_negx"], f[f"mac_out{sfx}_negwx"] = nw * one, nx * one, nwx * one
    f["input_neg"] = (tr.dk < 0).sum(1).astype(float)
    if s["residual"]:
        nz = (np.asarray(im.out.A1) != 0).astype(int) + (np.asarray(im.out.A0) != 0).astype(int)  # (n_out, n_in)
        f["affine_neg"] = ((tr.d < 0).astype(int) @ nz.sum(0)).astype(float)
    for v_in, T, hits in tr.layers:
        idx = tanh_class_index(V, T)
        for c in range(len(classes)):
            counts[:, c] += np.count_nonzero(idx == c, axis=1)
        sat_hits += hits
    for c, name in enumerate(classes):
        if c == 0:
            continue  # the reference class: its cost is in tanh[V]
        f[f"tanh_class[{V}][{name}]"] = counts[:, c]
    f["sat_hit"] = sat_hits
    f["dac_hit"] = dac_hits(im, in_um).astype(float)
    f = {k: np.broadcast_to(np.asarray(v, dtype=float), (N,)) for k, v in f.items()}
    return {k: np.asarray(v, dtype=float) for k, v in f.items() if np.any(v != 0) or k == "call"}


def size_features(im, far: bool = False, target: str | None = None) -> dict[str, float]:
    """Per-program flash/RAM features (far: see cycle_features)."""
    if getattr(im, "kernel", None) == "fast":
        return fast_size_features(im, far, target)
    s = structure(im)
    V = s["variant"]
    f = {
        "far_frame": float(far),
        "far_frame_multi": float(far and s["layers"] > 1),
        f"code[{V}]": 1.0,
        f"code_multi[{V}]": float(s["layers"] > 1),
        "deep_layer": float(max(s["layers"] - 2, 0)),
        "table_bytes": float(s["table_bytes"]),
        "output": float(s["n_out"]),
        "output_e_pos": float(s["n_out"] * (s["e"] > 0)),
        "output_e_neg": float(s["n_out"] * (s["e"] < 0)),
        "affine_term": float(s["n_out"] * s["n_in"] if s["residual"] else 0),
        "residual": float(s["residual"]),
        **{f"affine_mul[{c}]": float(n) for c, n in s["affine_mul"].items()},
        "dac_clamp": float(s["n_out"] if s["dac"] else 0),
        "sat_layer": float(s["sat_layers"]),
        "input_k0": float(s["k0"]),
        "weights_w8": float(s["weight_bits"] == 8),
        "widest": float(s["widest"]),
        "tanh_table": float(_tanh_table_bytes(V)),
        # an inlined tanh (one hidden layer) loses the branches its input range cannot reach
        **{f"tanh_dead[{V}][{b}]": 1.0 for b in _dead_tanh_regions(im)},
    }
    return {k: v for k, v in f.items() if v != 0 or k.startswith("code[")}


def frame_features(im) -> dict[str, float]:
    """Features of the AVR stack frame size of NAME_ik (locals a[widest], h[widest], d[], spills)."""
    s = structure(im)
    multi = s["layers"] > 1
    f = {("frame_multi" if multi else f"frame_one[{s['variant']}]"): 1.0,
         ("frame_widest_multi" if multi else "frame_widest_one"): float(s["widest"]),
         "frame_residual": float(s["residual"]), "frame_w8": float(s["weight_bits"] == 8),
         "frame_dac": float(s["dac"])}
    return {k: v for k, v in f.items() if v != 0}


def predict_frame(im, frame_model: dict | None) -> float | None:
    if not frame_model:
        return None
    return float(sum(frame_model["coef"].get(k, 0.0) * v for k, v in frame_features(im).items()))


def is_far(frame: float | None, frame_model: dict | None) -> bool:
    return frame is not None and frame_model is not None and frame > frame_model.get("far_above", 66)


def _dead_tanh_regions(im) -> list[str]:
    """Regions/segments of the tanh that a compiler can prove unreachable when tanh is inlined
    into the only hidden layer: T = (acc + 2^(sh-1)) >> sh of an int32 has |T| <= 2^(31-sh)."""
    from nnik.implementations.mlp import tanh as activations

    if len(im.hidden) != 1 or im.hidden[0].saturate:
        return []
    L = im.hidden[0]
    if getattr(L, "tanh_step", 0):
        return []
    amax = min(2 ** (31 - int(L.sh)), 32768)
    v = activations.get_variant(im.tanh_variant)
    dead = []
    if v.kind == "lerp":
        for i, rg in enumerate(v.regions):
            if rg["a_lo"] > amax:
                dead.append(f"r{i}")
        if v.sat_a > amax:
            dead.append("sat")
    elif v.kind == "poly":
        for i, sg in enumerate(v.segments):  # branches (breakpoints) or table rows (|v| >> k)
            if sg["a_lo"] > amax:
                dead.append(f"s{i}")
        if v.sat_a > amax:
            dead.append("sat")
    return dead


def _tanh_table_bytes(variant) -> int:
    from nnik.implementations.mlp import tanh as activations

    return int(activations.get_variant(variant).coeff_bytes)


# which features each size quantity is fitted on
FLASH_FEATURES = ("code[", "code_multi[", "tanh_dead[", "deep_layer", "far_frame", "far_frame_multi", "table_bytes", "output", "output_e_pos", "output_e_neg",
                  "affine_term", "affine_mul[", "residual", "dac_clamp", "sat_layer", "input_k0", "weights_w8")
RAM_FEATURES = ("code[", "code_multi[", "widest", "output", "residual", "weights_w8")


def _select(feats: dict, prefixes: Sequence[str]) -> dict:
    return {k: v for k, v in feats.items() if any(k == p or (p.endswith("[") and k.startswith(p)) for p in prefixes)}


def flash_features(sf: dict) -> dict:
    if any(":" in k for k in sf):  # fast kernel: every count is code
        return {k: v for k, v in sf.items() if not k.endswith(":widest")}
    return _select(sf, FLASH_FEATURES)


def ram_features(sf: dict) -> dict:
    if any(":" in k for k in sf):
        return {k: v for k, v in sf.items() if k.split(":", 1)[1] in ("call", "widest", "multi_layer", "residual",
                                                                       "weights_w8", "loop_neuron")}
    return _select(sf, RAM_FEATURES)
