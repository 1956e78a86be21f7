"""The neural controllers' fixed-point formats, chosen by range analysis (the Python spec of
codegen/arduino/src/nnik_ctl_nn.h, bit for bit). Every product is int16 x int16 -> int32; no
float, no int64, no 32 x 32 product except the vector split's unit vector (nn_vector.py).

    x_i    inputs, int16 Q3.12 (|x| <= 32767: +-8.0): raw integer input (counts) scaled by a power of
           two 2^s (s = in_shift[i], -12 .. 12) and saturated: s >= 0: sat(raw, 32767 >> s) * 2^s
           (saturate first, so nothing overflows); s < 0: sat(raw >> -s, 32767) (arithmetic shift).
    w1     master words int32 Q3.28, clamped to +-2^30 (+-4.0); the forward pass uses w1 >> 16, int16
           Q3.12 in [-16384, 16384]. Range: 4 x 16384 x 32767 < 2^31, so the hidden sum cannot wrap.
    a_j    sum_i (w1_ji >> 16) x_i is Q6.24 int32; a_j = sat16(sum >> 12), Q3.12 (tanh is 1.0 in Q15
           from 5.5 on, so saturating at 8.0 changes nothing).
    h_j    tanh_int(a_j) (nnik.implementations.mlp.tanh, variant lerp_mr4): Q15, |h| <= 32767.
    w2     master words int32 Q3.28 of the NORMALISED output (u / 2^b, b = bit length of duty_max:
           1.0 = 256 duty on 8-bit PWM), clamped to +-2^29 (+-2.0); forward uses w2 >> 16, int16 Q12
           in [-8192, 8192]. Range: 8 x 8192 x 32767 < 2^31.
    y      sum_j (w2_j >> 16) h_j, Q27 normalised; the Q8 duty accumulator is y >> (19 - b), then
           rounded half up and saturated to +-duty_max (servo.fixed.duty_out).
    d      delta_out, int16 Q3.12: nn_axes sat16((x_0 J) >> 12) with J int16 Q12 (the axis' Jacobian),
           x_0 the net's own (scaled, saturated) error input; nn_vector: d = x_0 = scaled |e| >= 0.
    g_j    1 - h_j^2 = 32767 - (h_j h_j >> 15), Q15 in [1, 32767].
    dh_j   delta_h = (sat16((d (w2_j >> 16)) >> 12) g_j) >> 15, int16 Q12 (saturates at 8.0).
    dW2_j  = rnd(rnd(d, eta & 7) h_j, eta & ~7)        Q27 product into the Q28 master: learning
                                                       rate 2^(1 - eta) in real units
    dW1_ji = rnd(rnd(dh_j, s1 & 7) x_i, s1 & ~7)       s1 = eta + 3 (a Q24 product): the same rate
           rnd(p, s) = (p + (2^s >> 1)) >> s, rounding half up. The rate's low bits shift the int16
           delta once per unit, its whole bytes the product (byte moves on the AVR: a 32-bit shift by
           a constant costs 6 cycles a bit there). |p| < 2^30, so master + dW < 2^31 before the
           clamp. eta = eta_shift, 0 .. 27.

Which weights learn on a tick: all 8 output weights, and the first-layer rows of the hidden units
j = k mod w1_every (params.py); a tick whose previous output sat at +-duty_max with d pushing it
further learns nothing (anti-windup, counted as held). A master word beyond its clamp is set to it
and counted (clamps); updates counts the words updated.

The weights' checksum is the sum of every master word's low 16 bits, mod 2^16 (uint16).

The activation is tanh_int's default variant lerp_mr4 (a 4-region table of 129 Q15 nodes with
linear interpolation: 1 multiply, 258 bytes, max 1.8 LSB): of the registered variants it is among
the cheapest on the AVR (measured in this session on simavr, per call with the harness's
overhead: lerp_mr4 259 cycles, lerp64 249, lerp_mr 254, lerp32 316, minimax2_x22 508, paper_lsq5
1719) and the smallest table of the fast ones.
"""

from __future__ import annotations

import functools

import numpy as np

from nnik.errors import NnikError

N_IN, N_HID = 4, 8
I16 = 32767
W1_LIM = 1 << 30  # master word clamp, Q3.28: +-4.0
W2_LIM = 1 << 29  # master word clamp, Q3.28 normalised output: +-2.0
MASTER_FRAC = 28  # master words: real = word / 2^28 (both layers)
Q_IN = 12  # inputs, hidden sums and the deltas
Q_J = 12  # the Jacobian
W1_EXTRA = 3  # the first layer's learning shift is eta + 3 (the same real learning rate)
ETA_MAX = 27
IN_SHIFT_MAX = 12
TANH_VARIANT = "lerp_mr4"


def sat(v: int, lim: int) -> int:
    return lim if v > lim else -lim if v < -lim else v


def scale_in(raw: int, s: int) -> int:
    """A raw integer input into Q3.12 by 2^s, saturated to +-32767 (see the module docstring)."""
    if s >= 0:
        return sat(raw, I16 >> s) << s
    return sat(raw >> -s, I16)


def rnd(p: int, s: int) -> int:
    """p / 2^s rounded half up (arithmetic shift)."""
    return (p + ((1 << s) >> 1)) >> s


def out_shift(duty_max: int) -> int:
    """y (Q27 normalised) >> out_shift = the Q8 duty accumulator: 19 - bit length of duty_max."""
    return 19 - int(duty_max).bit_length()


@functools.lru_cache(maxsize=1)
def tanh_table() -> tuple[int, ...]:
    """tanh_int of every int16 input, indexed by v + 32768 (the generated C, bit for bit)."""
    from nnik.implementations.mlp.tanh import tanh_int

    return tuple(int(t) for t in tanh_int(np.arange(-32768, 32768), TANH_VARIANT))


def tanh_c() -> str:
    """The C of the activation (static int16_t nnik_tanh(int16_t), tables in flash)."""
    from nnik.implementations.mlp.tanh import render_tanh_c

    return render_tanh_c(TANH_VARIANT, prefix="nnik")


def check_int(name: str, v, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= int(v) <= hi:
        raise NnikError(f"neural controller params: {name} must be an integer in {lo} .. {hi}, not {v!r}")
    return int(v)
