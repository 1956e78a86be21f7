"""The tool in step with the shaped head: nnik_sh_tool (codegen/arduino/src/nnik_shaper.c), bit
for bit, over a whole stream at once.

The planner's arc length Q (increments ds = ceil(v / 2^15), half micrometres per sample) goes
through axis 0's shaper taps like a position; the shaped head has run Qs[n] = Q[n] - lag[n],
lag = (16384 + sum_i A_i (Q[n] - Q[n - d_i])) >> 15.  Sample n gets the planned duty of sample m,
the first at or after the previous m and n - shaper_len with Q[m] >= Qs[n]: the tool switches when
the shaped head reaches the planned switch.  M4's planned duty is scaled by the shaped speed over
the planned one, (Qs[n] - Qs[n - 1]) / ds[m], capped at 255.  Before the first sample every past
sample is at rest with duty 0.  Rests (kind 1) keep their own duty and do not step it.
"""

from __future__ import annotations

import numpy as np

M4 = 0x100  # program.TOOL_SCALED


def planned_duty(tool: np.ndarray, v: np.ndarray, vn: np.ndarray) -> np.ndarray:
    """OCR2A of the planned sample: the tool word's duty; M4 scaled by min(v, vn) / vn."""
    base = tool & 0xFF
    return np.where((tool & M4) != 0, base * np.minimum(v, vn) // vn, base)


def shaped_duty(pd: np.ndarray, v: np.ndarray, m4: np.ndarray, taps, length: int) -> np.ndarray:
    """The duty of each sample given its planned duty pd, planned speed v (Q16 um/sample) and M4
    flag, through the taps (amplitudes, delays) of a shaper of `length` samples."""
    n = len(pd)
    if not length or not n:
        return pd.copy()
    R = length + 1  # the virtual past: R samples at rest, duty 0
    ds = np.concatenate([np.zeros(R, np.int64), (v + 0x7FFF) >> 15])
    Q = np.cumsum(ds)
    lag = np.full(n, 16384, np.int64)
    amps, delays = taps
    for A, d in zip(amps, delays):
        if d:
            lag += A * (Q[R:] - Q[R - d:R - d + n])
    lag >>= 15
    Qs = Q[R:] - lag
    first = np.searchsorted(Q, Qs, side="left")
    m = np.maximum(np.maximum.accumulate(np.maximum(first, R - 1)), np.arange(R, R + n) - length)
    vs = np.diff(np.concatenate([[0], Qs]))
    pdm, dsm = np.concatenate([np.zeros(R, np.int64), pd])[m], ds[m]
    m4m = np.concatenate([np.zeros(R, bool), m4 != 0])[m] & (dsm != 0)
    scaled = np.minimum(pdm * np.maximum(vs, 0) // np.where(dsm != 0, dsm, 1), 255)
    return np.where(m4m, scaled, pdm)


def stream_duty(kind, speed, vn, tool, cfg=None) -> np.ndarray:
    """OCR2A of every segment of a stream (planner.Stream's columns): a rest's tool word is its
    duty; a sample's is planned_duty, and with cfg's shaper, shaped_duty."""
    kind, speed, vn, tool = (np.asarray(c, dtype=np.int64) for c in (kind, speed, vn, tool))
    pd = planned_duty(tool, speed, np.maximum(vn, 1))
    if cfg is None or not cfg.shaper_len:
        return pd
    out = pd.copy()
    samp = kind == 0
    out[samp] = shaped_duty(pd[samp], speed[samp], tool[samp] & M4, cfg.shaper_taps[0], cfg.shaper_len)
    return out
