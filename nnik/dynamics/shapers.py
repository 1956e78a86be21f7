"""Input shapers ZV, MZV, ZVD, EI, 2HUMP_EI and 3HUMP_EI from a resonance (f, zeta), their
residual vibration, and their fixed-point form for the firmware.

The formulas are the standard ones (Singer & Seering), as Klipper's klippy/extras/shaper_defs.py
publishes them: with the damped period T_d = 1 / (f sqrt(1 - zeta^2)) and
K = exp(-zeta pi / sqrt(1 - zeta^2)),
  ZV:  [1, K] / (1 + K) at [0, T_d / 2];
  ZVD: [1, 2K, K^2] / (1 + K)^2 at [0, T_d / 2, T_d];
  MZV: three impulses over 0.75 T_d (zero vibration at f, a wider notch than ZV);
  EI:  three impulses over T_d, with 5 % vibration allowed at f for a wide band (a cubic fit
       of the middle impulse's time over zeta);
  2HUMP_EI, 3HUMP_EI: four and five impulses over 1.5 and 2 periods (1 / f), each amplitude and
       time a cubic in zeta (the published expansion coefficients, HUMP_EI below).
Klipper's fits hold up to a damping ratio per shaper (MAX_ZETA); above it design() refuses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

KINDS = ("zv", "mzv", "zvd", "ei", "2hump_ei", "3hump_ei")
EI_TOLERANCE = 0.05  # the residual vibration EI allows at its design frequency
# the largest damping ratio each shaper's design holds to (Klipper's max_damping_ratio)
MAX_ZETA = {"zv": 0.99, "mzv": 0.99, "zvd": 0.99, "ei": 0.4, "2hump_ei": 0.3, "3hump_ei": 0.2}
# the multi-hump EI shapers: per impulse, the cubic in zeta of its time (in periods 1 / f) and of
# its amplitude (Singer & Seering's fit, as Klipper's shaper_defs lists it)
HUMP_EI = {
    "2hump_ei": (((0.0, 0.0, 0.0, 0.0), (0.49890, 0.16270, -0.54262, 6.16180),
                  (0.99748, 0.18382, -1.58270, 8.17120), (1.49920, -0.09297, -0.28338, 1.85710)),
                 ((0.16054, 0.76699, 2.26560, -1.22750), (0.33911, 0.45081, -2.58080, 1.73650),
                  (0.34089, -0.61533, -0.68765, 0.42261), (0.15997, -0.60246, 1.00280, -0.93145))),
    "3hump_ei": (((0.0, 0.0, 0.0, 0.0), (0.49974, 0.23834, 0.44559, 12.4720),
                  (0.99849, 0.29808, -2.36460, 23.3990), (1.49870, 0.10306, -2.01390, 17.0320),
                  (1.99960, -0.28231, 0.61536, 5.40450)),
                 ((0.11275, 0.76632, 3.29160, -1.44380), (0.23698, 0.61164, -2.57850, 4.85220),
                  (0.30008, -0.19062, -2.14560, 0.13744), (0.23775, -0.73297, 0.46885, -2.08650),
                  (0.11244, -0.45439, 0.96382, -1.46000))),
}
Q = 15  # amplitudes in Q15: they sum to exactly 1 << Q


@dataclass(frozen=True)
class Shaper:
    kind: str
    f_hz: float
    zeta: float
    amps: tuple[float, ...]  # sum to 1
    times_s: tuple[float, ...]  # the first is 0

    @property
    def duration_s(self) -> float:
        return self.times_s[-1]


def design(kind: str, f_hz: float, zeta: float) -> Shaper:
    """The shaper of kind for a resonance at f_hz with damping ratio zeta (0 <= zeta < 1)."""
    if kind not in KINDS:
        raise ValueError(f"unknown shaper {kind!r}; choose one of none, {', '.join(KINDS)}")
    if not (math.isfinite(f_hz) and f_hz > 0):
        raise ValueError(f"shaper frequency must be > 0 Hz, got {f_hz}")
    if not 0 <= zeta < 1:
        raise ValueError(f"shaper damping ratio must be in [0, 1), got {zeta} (zeta >= 1 is overdamped: nothing rings)")
    if zeta > MAX_ZETA[kind]:
        raise ValueError(f"{kind} holds to a damping ratio of {MAX_ZETA[kind]:g} (Klipper's limit), got {zeta:g}")
    if kind in HUMP_EI:
        times, amps = HUMP_EI[kind]
        a, t = [_cubic(c, zeta) for c in amps], [_cubic(c, zeta) / f_hz for c in times]
        s = sum(a)
        return Shaper(kind, float(f_hz), float(zeta), tuple(x / s for x in a), tuple(t))
    root = math.sqrt(1.0 - zeta * zeta)
    t_d = 1.0 / (f_hz * root)
    if kind == "zv":
        k = math.exp(-zeta * math.pi / root)
        a, t = [1.0, k], [0.0, 0.5 * t_d]
    elif kind == "zvd":
        k = math.exp(-zeta * math.pi / root)
        a, t = [1.0, 2.0 * k, k * k], [0.0, 0.5 * t_d, t_d]
    elif kind == "mzv":
        k = math.exp(-0.75 * zeta * math.pi / root)
        a1 = 1.0 - 1.0 / math.sqrt(2.0)
        a, t = [a1, (math.sqrt(2.0) - 1.0) * k, a1 * k * k], [0.0, 0.375 * t_d, 0.75 * t_d]
    else:  # ei: the fit of the extra-insensitive shaper's impulses over zeta (Singer, Seering)
        v = EI_TOLERANCE
        a1 = (0.24968 + 0.24961 * v) + (0.80008 + 1.23328 * v) * zeta + (0.49599 + 3.17316 * v) * zeta**2
        a3 = (0.25149 + 0.21474 * v) + (-0.83249 + 1.41498 * v) * zeta + (0.85181 - 4.90094 * v) * zeta**2
        t2 = 0.4999 + _cubic((0.0, (0.46159 + 8.57843 * v) * v, (4.26169 - 108.644 * v) * v, (1.75601 + 336.989 * v) * v), zeta)
        a, t = [a1, 1.0 - a1 - a3, a3], [0.0, t2 * t_d, t_d]
    s = sum(a)
    return Shaper(kind, float(f_hz), float(zeta), tuple(x / s for x in a), tuple(t))


def _cubic(c, x: float) -> float:
    return c[0] + x * (c[1] + x * (c[2] + x * c[3]))


def response(amps, times_s, freqs, zeta: float) -> np.ndarray:
    """Residual vibration of an impulse train on modes at freqs (Hz, an array) with damping ratio
    zeta, as a fraction of the unshaped one's (1.0: no reduction): Klipper's shaper response."""
    w = 2.0 * np.pi * np.asarray(freqs, float)[:, None]
    wd = w * math.sqrt(max(1.0 - zeta * zeta, 0.0))
    a, t = np.asarray(amps, float), np.asarray(times_s, float)
    e = a * np.exp(zeta * w * (t - t[-1]))
    return np.hypot(np.sum(e * np.cos(wd * t), axis=1), np.sum(e * np.sin(wd * t), axis=1)) / np.sum(a)


def residual(amps, times_s, f_hz: float, zeta: float) -> float:
    """response() at one frequency f_hz."""
    return float(response(amps, times_s, [f_hz], zeta)[0])


def quantize(shaper: Shaper, sample_hz: int) -> tuple[list[int], list[int]]:
    """(amplitudes in Q15 summing to exactly 32768, delays in whole samples at sample_hz), in
    ascending delay.  An impulse at a time between two samples is split between them in
    proportion (linear interpolation of the delay), so the notch stays at f however the period
    falls on the sample grid; taps under 1/2^15 are dropped.  Each amplitude is rounded, and the
    largest takes the rounding's remainder."""
    taps: dict[int, float] = {}
    for a, t in zip(shaper.amps, shaper.times_s):
        pos = t * sample_hz
        k = math.floor(pos + 1e-9)
        frac = pos - k if pos - k > 1e-9 else 0.0
        taps[k] = taps.get(k, 0.0) + a * (1.0 - frac)
        if frac:
            taps[k + 1] = taps.get(k + 1, 0.0) + a * frac
    delays = sorted(d for d, a in taps.items() if round(a * (1 << Q)) > 0)
    amps = [int(round(taps[d] * (1 << Q))) for d in delays]
    amps[int(np.argmax(amps))] += (1 << Q) - sum(amps)
    return amps, delays


def quantized_residual(shaper: Shaper, sample_hz: int, f_hz: float | None = None, zeta: float | None = None) -> float:
    """The residual vibration of the firmware's shaper (quantised amplitudes and delays)."""
    amps, delays = quantize(shaper, sample_hz)
    return residual(amps, [d / sample_hz for d in delays], shaper.f_hz if f_hz is None else f_hz,
                    shaper.zeta if zeta is None else zeta)


def axis_taps(kind: str, dynamics: dict, sample_hz: int) -> tuple:
    """Per axis (Q15 amplitudes, delays in samples) of the shaper kind for the [dynamics]
    resonance {"f_hz": (fx, fy), "zeta": (zx, zy)}: designed, then quantised."""
    out = []
    for f, z in zip(dynamics["f_hz"], dynamics["zeta"]):
        amps, delays = quantize(design(kind, float(f), float(z)), sample_hz)
        out.append((tuple(int(a) for a in amps), tuple(int(d) for d in delays)))
    return tuple(out)
