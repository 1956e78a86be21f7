"""The integer arithmetic every servo controller shares (the Python spec of codegen/arduino/src/
nnik_ctl_fix.h, bit for bit).

Formats (chosen by range analysis; docs/closed_loop.md "Controllers"):
- positions and references: int32 encoder counts (200 mm = 80,000 counts at 2.5 um a count);
- an error, a speed or an acceleration entering a product is saturated to int16, +-32,767 counts
  (+-82 mm at 2.5 um): every product is then 16 x 16 -> 32 bits, the AVR's cheap widening multiply
  (no 32 x 32 and no int64 anywhere in a tick);
- gains are unsigned 16-bit fixed point: Q8.8 duty per count (proportional, derivative and the
  feedforwards), Q0.16 duty per count per tick (integral);
- each product term is saturated to +-2^28 (Q8 duty: +-1,048,576 duty, 4,096 x duty_max at 8 bits)
  before the terms are summed, so a sum of up to seven terms stays inside int32. The result differs
  from unbounded arithmetic only when two terms, each beyond a million duty, oppose each other;
- the output is accumulated in Q8 duty (1/256 duty), rounded half up ((q + 128) >> 8, an
  arithmetic shift: gcc and avr-gcc shift signed values arithmetically) and saturated to
  [-duty_max, duty_max].
"""

from __future__ import annotations

import math

from nnik.errors import NnikError

I16 = 32767
TERM = 1 << 28  # a product term's saturation, Q8 duty
Q_OUT = 8  # the output accumulator's fraction bits
Q_GAIN = 8  # Q8.8 gains
Q_INT = 16  # Q0.16 integral gain; the integral is kept in Q16 duty
U16 = 65535


def sat(v: int, lim: int) -> int:
    """v saturated to [-lim, lim]."""
    return lim if v > lim else -lim if v < -lim else v


def s16(v: int) -> int:
    return sat(v, I16)


def term(gain_q: int, x: int) -> int:
    """gain (unsigned Q) * x (int16), saturated to +-TERM."""
    return sat(gain_q * x, TERM)


def duty_out(acc_q8: int, duty_max: int) -> int:
    """The Q8 accumulator rounded half up and saturated to the duty range."""
    return sat((acc_q8 + (1 << (Q_OUT - 1))) >> Q_OUT, duty_max)


def quantise(name: str, value: float, frac_bits: int) -> int:
    """A non-negative gain in unsigned 16-bit fixed point with frac_bits fraction bits; one NnikError
    line when it does not fit."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise NnikError(f"controller gain {name} must be a number, not {value!r}") from None
    top = U16 / (1 << frac_bits)
    if not math.isfinite(v) or v < 0 or round(v * (1 << frac_bits)) > U16:
        raise NnikError(f"controller gain {name} = {value!r} is outside its format's range 0 .. {top:.6g}")
    return round(v * (1 << frac_bits))
