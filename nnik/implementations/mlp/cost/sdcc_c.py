"""The fast kernel's C path under SDCC (PIC18): its counts by the code SDCC runs.

fast_features counts the C path by construct and layer, with every constant shift split by
regime (the form avr-gcc's code takes).  Under SDCC the same constructs are fewer distinct
pieces of code (nnik_kernel.h, "portable C (and SDCC's C parts)"):

* every multiply-accumulate is one call of SDCC's 32-bit multiply plus a 32-bit add or
  subtract, whichever layer it is in and whatever the weight's width (int8 weights are the same
  C as int16 ones);
* every 32-bit shift by a constant n is a call of nnik_shr32_fill: a byte loop run n >> 3 times
  and a bit loop run n & 7 times, after a set-up that depends on the call site (logical or
  arithmetic, the expression around it);
* the residual base d * A1 + (d * A0 >> P) >> (G - P) multiplies whatever A is;
* a negative output exponent multiplies by 2^-e (the 32-bit multiply, not a shift).

Fitting these with a coefficient per layer, per weight class and per shift regime, as the
regime form does, leaves most coefficients determined by a handful of calibration networks:
a network of the search space then combines them in proportions no calibration network had
(issue 25: the C path of small networks was off by up to 17 % on PIC18).  Here each shift site
counts once per kind (its set-up) plus its byte and bit loop iterations, each multiply once.
"""

from __future__ import annotations

import re

# regime-split shift features of fast_features: NAME[lo_hi] (sites) and NAME_n[lo_hi] (sum of n)
_SHIFT = re.compile(r"^(?P<name>[a-z_A-Z]+?)(?P<n>_n)?\[(?P<lo>\d+)(?:_(?P<hi>\d+))?\]$")
_SHIFT_KINDS = ("input_k", "t_sh", "out_foldF", "out_F", "out_e_pos", "aff_p", "aff_gp")
# the same C whatever the layer or the weight's width
_MERGE = {"mac_first_u8": "mac", "mac_first_u16": "mac", "mac_hidden_u8": "mac", "mac_hidden_u16": "mac",
          "mac_out_u8": "mac", "mac_out_u16": "mac"}
_DROP_PREFIX = ("affine_mul[", "weights_w8")


def sdcc_c_counts(c: dict[str, float]) -> dict[str, float]:
    """The regime-form counts of a fast network's C path, as SDCC's code runs them."""
    out: dict[str, float] = {}

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
        if m and m["name"] == "out_e_neg":  # a multiply by 2^-e: one site, whatever e
            if not m["n"]:
                add("out_e_neg", v)
            continue
        if k.startswith(_DROP_PREFIX):
            continue
        add(_MERGE.get(k, k), v)
    for (name, lo), n_sites in sites.items():
        total = nsum.get((name, lo), 0.0)
        nbytes = n_sites * (lo >> 3)  # every regime lies within one byte count
        # a shift by 16 of the tanh input is nnik_tu16 (no arithmetic fill): its own set-up
        site = "t16" if name == "t_sh" and lo == 16 else name
        add(f"{site}:site", n_sites)
        add(f"{name}:bytes", nbytes)
        add(f"{name}:bits", total - 8 * nbytes)
    return out
