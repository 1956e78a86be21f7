"""The tool in step with the shaped head: nnik_sh_step's nnik_sh_tool (codegen/arduino/src/
nnik_shaper.h), bit for bit, over a whole stream at once.

The planner's progress Q (its path length, in units of 2^(psh - 16) um: Q[n] = floor(sum of the
samples' path lengths moved (Q16 um) / 2^psh), psh = MachineConfig.progress_shift) goes through
axis 0's taps as a third axis: the shaped head's
progress is Q[n] + ((16384 - sum_i A_i (Q[n] - Q[n - d_i])) >> 15), lag[n] the minus of that
shift.  Sample n gets the planned duty of sample m, the first at or after the
previous m and n - shaper_len + 1 with Q[m] >= Q[n] - lag[n]: the tool switches when the shaped
head reaches the planned switch.  Before the first sample every past sample is at rest with duty
0.  Rests (kind 1) keep their own duty and do not step it.
"""

from __future__ import annotations

import numpy as np

M4 = 0x100  # program.TOOL_SCALED


def planned_duty(tool: np.ndarray, v: np.ndarray, vn: np.ndarray) -> np.ndarray:
    """OCR2A of the planned sample: the tool word's duty; M4 scaled by min(v, vn) / vn."""
    base = tool & 0xFF
    return np.where((tool & M4) != 0, base * np.minimum(v, vn) // vn, base)


def shaped_duty(pd: np.ndarray, moved: np.ndarray, taps, length: int, psh: int) -> np.ndarray:
    """The duty of each sample given its planned duty pd and the path length it moved (Q16 um)
    (the shaper starts at rest), through the taps (amplitudes, delays) of a shaper of `length`,
    the progress in units of 2^(psh - 16) um."""
    n = len(pd)
    if not length or not n:
        return pd.copy()
    R = length  # the virtual past: R samples at rest, duty 0
    Q = np.concatenate([np.zeros(R, np.int64), np.cumsum(np.asarray(moved, dtype=np.int64)) >> psh])
    acc = np.full(n, 16384, np.int64)
    for A, d in zip(*taps):
        if d:
            acc -= A * (Q[R:] - Q[R - d:R - d + n])
    lag = -(acc >> 15)
    first = np.searchsorted(Q, Q[R:] - lag, side="left")
    m = np.maximum(np.maximum.accumulate(np.maximum(first, R - 1)), np.arange(R, R + n) - (length - 1))
    return np.concatenate([np.zeros(R, np.int64), pd])[m]


def stream_duty(kind, speed, vn, tool, moved=None, cfg=None) -> np.ndarray:
    """OCR2A of every segment of a stream (planner.Stream's columns): a rest's tool word is its
    duty; a sample's is planned_duty, and with cfg's shaper, shaped_duty."""
    kind, speed, vn, tool = (np.asarray(c, dtype=np.int64) for c in (kind, speed, vn, tool))
    pd = planned_duty(tool, speed, np.maximum(vn, 1))
    if cfg is None or not cfg.shaper_len:
        return pd
    out = pd.copy()
    samp = kind == 0
    out[samp] = shaped_duty(pd[samp], np.asarray(moved, dtype=np.int64)[samp], cfg.shaper_taps[0], cfg.shaper_len,
                            cfg.progress_shift)
    return out
