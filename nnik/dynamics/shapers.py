"""Input shapers ZV, MZV, ZVD and EI from a resonance (f, zeta), their residual vibration, and
their fixed-point form for the firmware.

The formulas are the standard ones (Singer & Seering; the same as Klipper's shaper_defs): with
the damped period T_d = 1 / (f sqrt(1 - zeta^2)) and K = exp(-zeta pi / sqrt(1 - zeta^2)),
  ZV:  [1, K] / (1 + K) at [0, T_d / 2];
  ZVD: [1, 2K, K^2] / (1 + K)^2 at [0, T_d / 2, T_d];
  MZV: three impulses over 0.75 T_d (zero vibration at f, a wider notch than ZV);
  EI:  three impulses over T_d, with 5 % vibration allowed at f for a wide band.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

KINDS = ("zv", "mzv", "zvd", "ei")
EI_TOLERANCE = 0.05  # the residual vibration EI allows at its design frequency
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
        t2 = 0.4999 + (0.46159 + 8.57843 * v) * v * zeta + (4.26169 - 108.644 * v) * v * zeta**2
        a, t = [a1, 1.0 - a1 - a3, a3], [0.0, t2 * t_d, t_d]
    s = sum(a)
    return Shaper(kind, float(f_hz), float(zeta), tuple(x / s for x in a), tuple(t))


def residual(amps, times_s, f_hz: float, zeta: float) -> float:
    """Residual vibration of an impulse train on a mode (f_hz, zeta), as a fraction of the
    unshaped one's (1.0: no reduction)."""
    w = 2.0 * math.pi * f_hz
    wd = w * math.sqrt(max(1.0 - zeta * zeta, 0.0))
    a, t = np.asarray(amps, float), np.asarray(times_s, float)
    e = np.exp(zeta * w * (t - t[-1]))
    c, s = np.sum(a * e * np.cos(wd * t)), np.sum(a * e * np.sin(wd * t))
    return float(math.hypot(c, s) / np.sum(a))


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
