"""Features of the "fast" kernel (nnik.implementations.mlp.kernel, nnik.implementations.mlp.fastc): unrolled,
weights as constants in the code, prefixed by the code path ("asm" or "c") each target takes."""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp import fastc

from nnik.implementations.mlp import fastc_avr

from nnik.implementations.mlp import fastc_p18
from nnik.implementations.mlp.cost.sdcc_c import sdcc_c_counts, sdcc_finish_counts
from nnik.implementations.mlp.cost.structure import structure
from nnik.implementations.mlp.cost.trace import dac_hits, hidden_trace, tanh_class_index, tanh_classes

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


# Shifts by a constant amount n: each implementation is linear in n only between byte boundaries
# and the special cases of its code (AVR asm: 4-, 3- or 2-byte steps by the tanh input shift's
# range; SDCC: a byte loop then a bit loop; avr-gcc: byte moves or a loop), so every shift site
# counts once and by its amount within the regime n falls in (features NAME[r] and NAME_n[r]).
BYTE_REGIMES = ((1, 7), (8, 15), (16, 23), (24, 31))
T_REGIMES = ((1, 7), (8, 14), (15, 15), (16, 16), (17, 23), (24, 31))
F_REGIMES = ((1, 7), (8, 15), (16, 16), (17, 23), (24, 31))
K_REGIMES = ((1, 7), (8, 8))


def regime_of(n: int, regimes) -> str | None:
    for lo, hi in regimes:
        if lo <= n <= hi:
            return f"{lo}_{hi}" if lo != hi else str(lo)
    return None


def _shift_terms(c: dict, name: str, n: int, count: float, regimes) -> None:
    """Add `count` shift sites of amount n: NAME[regime] += count, NAME_n[regime] += count * n."""
    r = regime_of(int(n), regimes)
    if r is None or not count:
        return
    c[f"{name}[{r}]"] = c.get(f"{name}[{r}]", 0.0) + count
    c[f"{name}_n[{r}]"] = c.get(f"{name}_n[{r}]", 0.0) + count * n


def _fast_counts(im, target: str | None) -> tuple[str, dict[str, float]]:
    """Constant per-call counts of the fast kernel, prefixed by its code path."""
    s = structure(im)
    path = fast_path(im, target)
    o = im.out
    umax = _unroll_max()
    c: dict[str, float] = {"call": 1.0, "multi_layer": float(s["layers"] > 1), 
                           "neuron_first": float(s["H"][0]), "neuron_deep": float(s["neurons_deep"])}
    for K in np.asarray(im.inp.K).tolist():
        _shift_terms(c, "input_k", int(K), 1, K_REGIMES)
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
        _shift_terms(c, "t_sh", sh, H, T_REGIMES)
        if L.saturate:
            c["sat_clamp"] = c.get("sat_clamp", 0.0) + H
    if path == "c" and target == "avr" and s["residual"]:
        # avr-gcc -O2, one layer with a tanh replacement: a full network saves and restores its
        # sums around each call (4 ldd + 4 std a neuron), a residual one keeps them in the frame
        # (2 ldd a neuron): the residual's own cost per neuron (avr_static counts them)
        c["residual_neuron"] = float(s["neurons"])
    if path == "c" and target == "avr" and s["layers"] == 2:
        regs = AVR_HB0_IN_REGS if all(getattr(L, "tanh_step", 0) for L in im.hidden) else AVR_HB0_CALL_SAVED
        c["mac_hidden_frame"] = float(s["H"][1] * max(s["H"][0] - regs, 0))
    looped_out = any(int(np.asarray(L.W).size) > umax for L in im.hidden) and bool(
        int(np.asarray(im.hidden[-1].W).size) > umax)
    for k, n in _weight_classes(o.V, looped_out).items():
        c[f"mac_out_{k}"] = n
    e = 15 + int(o.g) - int(o.F)
    fold = e == 0 and not o.residual
    n_out = s["n_out"]
    if path != "asm" or not _asm_output_terms(c, im, n_out, target):
        _c_affine_terms(c, im, n_out)
    c["out_fold"] = float(n_out * fold)
    c["out_plain"] = float(n_out * (not fold))
    _shift_terms(c, "out_foldF" if fold else "out_F", int(o.F), n_out, F_REGIMES)
    if e > 0:
        _shift_terms(c, "out_e_pos", e, n_out, BYTE_REGIMES)
    elif e < 0:
        _shift_terms(c, "out_e_neg", -e, n_out, BYTE_REGIMES)
    c["affine_term"] = float(n_out * s["n_in"] if s["residual"] else 0)
    for cl, n in s["affine_mul"].items():
        c[f"affine_mul[{cl}]"] = float(n)
    c["residual"] = float(s["residual"])
    c["dac_clamp"] = float(n_out if s["dac"] else 0)
    c["weights_w8"] = float(s["weight_bits"] == 8)
    if path == "asm" and target == "avr" and "out_c_finish" in c:
        # the assembly body hands the raw accumulators to C (fastc_avr.output_asm_ok): avr-gcc's
        # shifts by e and F cost other cycles per bit than the assembly's, so they are counted apart
        c = {(f"cfin_{k}" if k.startswith(_OUT_SHIFTS) else k): v for k, v in c.items()}
    if target == "pic18" and path == "c":
        c = sdcc_c_counts(c, im)
    elif target == "pic18" and "out_c_finish" in c:
        c = sdcc_finish_counts(c, im)
    return path, {k: v for k, v in c.items() if v != 0 or k == "call"}


_OUT_SHIFTS = ("out_F", "out_foldF", "out_e_pos", "out_e_neg", "out_fold", "out_plain")


def _c_affine_terms(c: dict, im, n_out: int) -> None:
    """The residual affine base in C: floor(d A / 2^G) as (d A1 + (d A0 >> P)) >> (G - P)."""
    o = im.out
    if not o.residual:
        return
    for k in range(n_out):
        for j in range(int(im.shape[0])):
            P, G = int(o.P[k][j]), int(o.G[k][j])
            _shift_terms(c, "aff_p", P, 1, BYTE_REGIMES)
            _shift_terms(c, "aff_gp", G - P, 1, BYTE_REGIMES)


def _asm_output_terms(c: dict, im, n_out: int, target: str | None = None) -> bool:
    """The assembly bodies' output stage (fastc_avr.output_asm_ok; False: the raw accumulators
    are finished in C): in assembly, the affine base's 24 x 32 products skip the zero bytes of the
    coefficient and shift by G (nnik_mac48, NNIK_P18_P48)."""
    o = im.out
    if not fastc_avr.output_asm_ok(im):
        c["out_c_finish"] = float(n_out)
        return False
    if not o.residual:
        return True
    for k in range(n_out):
        for j in range(int(im.shape[0])):
            a = abs(fastc_avr.affine_a(o, k, j))
            G = int(o.G[k][j])
            nz = [b for b in range(4) if (a >> (8 * b)) & 0xFF]
            c["aff_bytes"] = c.get("aff_bytes", 0.0) + len(nz)
            if target == "avr":  # byte b of A adds into bytes b.. of the 48-bit sum: nnik_mac48x's
                # carry chain is one instruction shorter per byte position
                c["aff_byte_pos"] = c.get("aff_byte_pos", 0.0) + sum(nz)
            c["aff_shl"] = c.get("aff_shl", 0.0) + max(16 - G, 0)
            c["aff_sar"] = c.get("aff_sar", 0.0) + max(G - 16, 0)
    return True


def _prefixed(path: str, k: str) -> str:
    """The feature's key: its code path in front (unless it names one: sdcc_c.SHARED)."""
    return k if k.startswith(("c:", "asm:")) else f"{path}:{k}"


# avr-gcc keeps about this many layer-1 outputs of a two-layer C path in registers through layer 2
# (next to the accumulator, the two output sums, the weight, the zero, r0:r1 and Z for the table);
# each further one is read from the frame by every layer-2 neuron (nnik.bench.mlp_cost.avr_static:
# a layer-2 multiply-accumulate costs 25.5 cycles at widths up to 6, 27.5 at 17-20)
AVR_HB0_IN_REGS = 6
# with a tanh replacement, called in every layer-2 neuron, only the call-saved r2-r17 keep values
# across the calls: the two output sums and this many layer-1 outputs
AVR_HB0_CALL_SAVED = 4


def cycle_prefix(im, target: str | None) -> str:
    """The prefix of a network's cycle features: its code path, and on AVR, for the C path of two
    hidden layers, "c2" (the kernel's own tanh table, inline: the layer-1 outputs stay in registers
    through layer 2 up to AVR_HB0_IN_REGS of them) or "c2call" (a tanh replacement, called: what is
    live is saved around each call).  avr-gcc allocates registers differently in these and in the
    one-layer C path, so the same primitive costs other cycles in each: they are priced apart,
    each by calibration networks of its own shape."""
    path = fast_path(im, target)
    if path != "c" or target != "avr" or len(im.hidden) != 2:
        return path
    return "c2" if all(getattr(L, "tanh_step", 0) for L in im.hidden) else "c2call"


def _feature_key(path: str, k: str) -> str:
    """A feature's key under cycle_prefix `path`: a called tanh replacement runs the same function
    whatever calls it, so its cost (tanh[...], tanh_class[...]) keeps the C path's key."""
    return _prefixed("c" if path == "c2call" and k.startswith("tanh") else path, k)


def fast_counts_prefixed(im, far: bool, target: str | None) -> dict[str, float]:
    """The constant per-call cycle features, prefixed by the code path (cycle_prefix)."""
    _, c = _fast_counts(im, target)
    path = cycle_prefix(im, target)
    f = {_feature_key(path, k): float(v) for k, v in c.items()}
    if far:
        f[f"{path}:far_neuron"] = float(sum(structure(im)["H"]))
    return f


def fast_cycle_features(im, in_um: np.ndarray, far: bool, target: str | None) -> dict[str, np.ndarray]:
    path = cycle_prefix(im, target)
    N = len(in_um)
    one = np.ones(N)
    f = {k: v * one for k, v in fast_counts_prefixed(im, far, target).items()}
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
                    key = _feature_key(path, f"tanh_class[{V}][{name}]")
                    f[key] = f.get(key, 0) + \
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
    f = {_prefixed(path, k): v for k, v in c.items()}
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
