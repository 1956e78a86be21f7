"""The fast kernel's C path under SDCC (PIC18): its counts by the code SDCC runs.

fast_features counts the C path by construct and layer, with every constant shift split by
regime (the form avr-gcc's code takes).  Under SDCC the same constructs are fewer distinct
pieces of code (nnik_kernel.h, "portable C (and SDCC's C parts)"):

* every multiply-accumulate is one call of SDCC's 32-bit multiply plus a 32-bit add or
  subtract, whichever layer it is in and whatever the weight's width (int8 weights are the same
  C as int16 ones) -- except by 1, which SDCC folds (the generated assembly of a network with a
  weight of 1 has one multiply call less), and by 2^8, 2^16, 2^24, counted apart as byte moves
  (the rule the output exponent shows below; other powers of two call the multiply: gpsim);
* every 32-bit shift by a constant n is a call of nnik_shr32_fill: a byte loop run n >> 3 times
  and a bit loop run n & 7 times, after a set-up that depends on the call site (logical or
  arithmetic, the expression around it);
* the residual base d * A1 + (d * A0 >> P) >> (G - P) multiplies whatever A is and calls both
  shifts whatever P and G - P are (0 included: the sites are the affine terms);
* a negative output exponent multiplies by 2^-e: the 32-bit multiply, or byte moves when -e is
  8, 16 or 24 (gpsim: a 2-3-2 network with -e = 8 ran 370 cycles faster than its twin with 7);
* a tanh replacement costs, per call, what its input class costs (measured on its own:
  nnik.bench.mlp_cost.tanh_bench; the fit keeps those coefficients, tanh_coefs).

Fitting these with a coefficient per layer, per weight class and per shift regime, as the
regime form does, leaves most coefficients determined by a handful of calibration networks:
a network of the search space then combines them in proportions no calibration network had
(issue 25: the C path of small networks was off by up to 17 % on PIC18).  Here each shift site
counts once per kind (its set-up), every site's byte and bit loop iterations share one cost (one
function runs them all), each multiply counts once.
"""

from __future__ import annotations

import re

from nnik.implementations.mlp import fastc

# regime-split shift features of fast_features: NAME[lo_hi] (sites) and NAME_n[lo_hi] (sum of n)
_SHIFT = re.compile(r"^(?P<name>[a-z_A-Z]+?)(?P<n>_n)?\[(?P<lo>\d+)(?:_(?P<hi>\d+))?\]$")
_SHIFT_KINDS = ("input_k", "t_sh", "out_foldF", "out_F", "out_e_pos", "aff_p", "aff_gp")
# the same C whatever the layer or the weight's width
_MERGE = {"mac_first_u8": "mac", "mac_first_u16": "mac", "mac_hidden_u8": "mac", "mac_hidden_u16": "mac",
          "mac_out_u8": "mac", "mac_out_u16": "mac"}
_DROP_PREFIX = ("affine_mul[", "weights_w8")
# times nnik_shr32_fill runs per site: nnik_sar32 (a macro) names its argument twice, so the
# inner shift of the affine base, nnik_sar32(d A1 + nnik_sar32(d A0, P), G - P), runs twice
_RUNS = {"aff_p": 2}


def _mul_class(w: int) -> str | None:
    """How SDCC multiplies by the constant w (after inlining the primitive): folded (0, 1), byte
    moves (2^8, 2^16, 2^24) or a call of its 32-bit multiply (None; other powers of two too)."""
    a = abs(int(w))
    return "zero" if a == 0 else "one" if a == 1 else "bytes" if a in (1 << 8, 1 << 16, 1 << 24) else None


def _constant_multiplies(im, out: dict[str, float], weights: bool) -> None:
    """MACs (unrolled weights) and affine-base coefficients whose multiply SDCC folds: counted
    apart from the calls (A1 and A0 apart: nnik_sar32 names the inner
    product twice, the outer once more)."""
    import numpy as np

    def add(k: str, v: float) -> None:
        out[k] = out.get(k, 0.0) + v

    umax = int(fastc.UNROLL_MAX_WEIGHTS)
    mats = [np.asarray(L.W) for L in im.hidden if int(np.asarray(L.W).size) <= umax] if weights else []
    if weights and int(np.asarray(im.hidden[-1].W).size) <= umax:
        mats.append(np.asarray(im.out.V))
    for W in mats:
        for w in W.ravel().tolist():
            k = _mul_class(w)
            if k and k != "zero":  # (zero weights have no code)
                add(f"mac_{k}", 1.0)
    o = im.out
    if o.residual:
        for name, A in (("aff_a1", o.A1), ("aff_a0", o.A0)):
            for a in np.asarray(A).ravel().tolist():
                k = _mul_class(a)
                if k:
                    add(f"{name}[{k}]", 1.0)


# the one shift function's loop iterations: the same cost on the C path and in the C that
# finishes an assembly body's outputs (keys with the path already in front)
SHARED = {"shift:bytes": "c:shift:bytes", "shift:bits": "c:shift:bits"}
_OUTPUT_STAGE = ("out_", "aff_", "affine_")


def sdcc_finish_counts(c: dict[str, float], im) -> dict[str, float]:
    """The counts of an assembly body whose outputs are finished in C (fastc.finish_lines, the
    C path's output stage): that stage as SDCC runs it, its loop iterations on the C path's keys."""
    stage = {k: v for k, v in c.items() if k.startswith(_OUTPUT_STAGE)}
    out = {k: v for k, v in c.items() if k not in stage}
    for k, v in sdcc_c_counts(stage, im, weights=False).items():
        out[SHARED.get(k, k)] = v
    return out


def sdcc_c_counts(c: dict[str, float], im, weights: bool = True) -> dict[str, float]:
    """The regime-form counts of a fast network's C path, as SDCC's code runs them (weights:
    with the MACs' constant multiplies)."""
    out: dict[str, float] = {}
    _constant_multiplies(im, out, weights)

    def add(k: str, v: float) -> None:
        out[k] = out.get(k, 0.0) + v

    sites: dict[tuple[str, int], float] = {}
    nsum: dict[tuple[str, int], float] = {}
    for k, v in c.items():
        m = _SHIFT.match(k)
        if m and m["name"] in _SHIFT_KINDS:
            key = (m["name"], int(m["lo"]))
            (nsum if m["n"] else sites)[key] = (nsum if m["n"] else sites).get(key, 0.0) + v
            continue
        if m and m["name"] == "out_e_neg":  # a multiply by 2^-e: SDCC's 32-bit multiply, or byte
            if not m["n"]:                   # moves when -e is a whole number of bytes
                n = c.get(f"out_e_neg_n[{m['lo']}_{m['hi']}]", 0.0) / v
                add("out_e_neg" + ("[bytes]" if n % 8 == 0 else ""), v)
            continue
        if k.startswith(_DROP_PREFIX):
            continue
        add(_MERGE.get(k, k), v)
    for (name, lo), n_sites in sites.items():
        total = nsum.get((name, lo), 0.0)
        nbytes = n_sites * (lo >> 3)  # every regime lies within one byte count
        # a shift by 16 of the tanh input is nnik_tu16 (no arithmetic fill): its own set-up
        site = "t16" if name == "t_sh" and lo == 16 else name
        if name not in ("aff_p", "aff_gp"):  # the affine base shifts even by 0: affine_term counts its sites
            add(f"{site}:site", n_sites)
        runs = _RUNS.get(name, 1)
        add("shift:bytes", runs * nbytes)
        add("shift:bits", runs * (total - 8 * nbytes))
    return out


def tanh_coefs(bench: dict[str, dict[str, float]], path: str = "c") -> dict[str, float]:
    """Cycle coefficients of the tanh replacements from their measured classes
    (nnik.bench.mlp_cost.tanh_bench): tanh[V] is a call in the variant's first class, each other
    class adds its difference (fast_features counts them so).  A variant whose first class was
    not measured is left to the fit."""
    from nnik.implementations.mlp.cost.trace import tanh_classes

    out: dict[str, float] = {}
    for V, per in bench.items():
        names = tanh_classes(V)
        if names[0] not in per:
            continue
        out[f"{path}:tanh[{V}]"] = per[names[0]]
        for name in names[1:]:
            if name in per:  # a class no int16 input reaches (the zero class's minus) stays out
                out[f"{path}:tanh_class[{V}][{name}]"] = round(per[name] - per[names[0]], 2)
    return out
