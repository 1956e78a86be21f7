"""The three figures Klipper gives each input shaper, by its own criteria (klippy/extras/
shaper_calibrate.py; the formulas restated here, not its code):

vibration  the remaining vibrations on a power spectral density: the PSD above 1/20 of its peak
           (a shaper cuts vibration 20 times at most, so less is ignored), weighted by the
           shaper's response, over the same sum unweighted; the worst of the damping ratios
           0.075, 0.1 and 0.15 (the machine's true damping is not known), bins up to 200 Hz.
smoothing  how far the shaped path strays at a 90 or 180 degree turn at 5000 mm/s^2 with a
           square corner velocity of 5 mm/s (mm): with t_s = sum A_i T_i the shaper's shift,
           90: sqrt(2) sum_{T_i >= t_s} A_i (scv + a/2 (T_i - t_s)) (T_i - t_s),
           180: sum A_i a/2 (T_i - t_s)^2, the larger of the two.
max accel  the acceleration at which that smoothing reaches 0.12 mm (Klipper bisects; both
           offsets are linear in a, so here it is solved exactly).

Without a measurement, the PSD is the one Klipper's resonance test would measure on the modelled
axis: the tip's acceleration of a base-excited spring-damper (nnik.dynamics.axis) driven by the
test's sweep (amplitude per Hz, so power ~ f^2 |H(f)|^2), normalised as Klipper normalises it.
"""

from __future__ import annotations

import math

import numpy as np

from nnik.dynamics.shapers import design, response

MIN_FREQ, MAX_FREQ = 5.0, 200.0  # Klipper's analysed band (Hz)
TEST_ZETAS = (0.075, 0.1, 0.15)
VIBRATION_REDUCTION = 20.0
SCV = 5.0  # square corner velocity, mm/s
SMOOTHING_ACCEL = 5000.0  # mm/s^2
TARGET_SMOOTHING = 0.12  # mm
DEFAULT_ZETA = 0.1  # Klipper's default damping_ratio_x / _y
MODEL_BIN_HZ = 0.25


def normalize_psd(freqs: np.ndarray, psd: np.ndarray) -> np.ndarray:
    """Klipper's normalisation of a measured PSD: divided by (f + 0.1), and below 2 x MIN_FREQ
    damped by exp(1 - (2 MIN_FREQ / (f + 0.1))^2) (low-frequency noise)."""
    out = np.asarray(psd, float) / (freqs + 0.1)
    low = freqs < 2.0 * MIN_FREQ
    out[low] *= np.exp(1.0 - (2.0 * MIN_FREQ / (freqs[low] + 0.1)) ** 2)
    return out


def denormalize_psd(freqs: np.ndarray, psd: np.ndarray) -> np.ndarray:
    """normalize_psd undone (0 where its low-frequency factor underflowed to 0: near 0 Hz)."""
    out = np.asarray(psd, float) * (freqs + 0.1)
    factor = np.exp(1.0 - (2.0 * MIN_FREQ / (freqs + 0.1)) ** 2)
    low = freqs < 2.0 * MIN_FREQ
    out[low] = np.where(factor[low] > 1e-200, out[low] / np.maximum(factor[low], 1e-200), 0.0)
    return out


def mode_gain2(freqs: np.ndarray, f_hz: float, zeta: float) -> np.ndarray:
    """|H|^2 of the base-excited spring-damper, base acceleration to tip acceleration."""
    r = np.asarray(freqs, float) / f_hz
    num = 1.0 + (2.0 * zeta * r) ** 2
    return num / ((1.0 - r * r) ** 2 + (2.0 * zeta * r) ** 2)


def mode_psd(f_hz: float, zeta: float, freqs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(bins, normalised PSD) that the resonance test would measure on the axis (f_hz, zeta)."""
    if freqs is None:
        freqs = np.arange(0.0, MAX_FREQ + MODEL_BIN_HZ / 2, MODEL_BIN_HZ)
    return freqs, normalize_psd(freqs, freqs**2 * mode_gain2(freqs, f_hz, zeta))


def remaining_vibrations(amps, times_s, freqs: np.ndarray, psd: np.ndarray, zetas=TEST_ZETAS) -> tuple[float, np.ndarray]:
    """(the worst remaining-vibration fraction over zetas, the worst response per bin) on the
    bins up to MAX_FREQ of a normalised PSD."""
    keep = freqs <= MAX_FREQ
    freqs, psd = freqs[keep], psd[keep]
    floor = psd.max() / VIBRATION_REDUCTION
    total = np.maximum(psd - floor, 0.0).sum()
    worst, vals = 0.0, np.zeros_like(freqs)
    for z in zetas:
        v = response(amps, times_s, freqs, z)
        vals = np.maximum(vals, v)
        if total > 0:
            worst = max(worst, float(np.maximum(v * psd - floor, 0.0).sum() / total))
    return worst, vals


def _offsets(amps, times_s, scv: float) -> tuple[float, float, float]:
    """The 90 degree offset c90 + k90 a and the 180 degree one k180 a, in the acceleration a."""
    a, t = np.asarray(amps, float), np.asarray(times_s, float)
    a = a / a.sum()
    dt = t - float(np.sum(a * t))  # from the shaper's shift
    late = dt >= 0
    c90 = math.sqrt(2.0) * scv * float(np.sum(a[late] * dt[late]))
    k90 = math.sqrt(2.0) * 0.5 * float(np.sum(a[late] * dt[late] ** 2))
    return c90, k90, 0.5 * float(np.sum(a * dt**2))


def smoothing(amps, times_s, accel: float = SMOOTHING_ACCEL, scv: float = SCV) -> float:
    """Klipper's smoothing of a shaper (mm) at accel (mm/s^2) and scv (mm/s)."""
    c90, k90, k180 = _offsets(amps, times_s, scv)
    return max(c90 + k90 * accel, k180 * accel)


def max_accel(amps, times_s, scv: float = SCV, target: float = TARGET_SMOOTHING) -> float:
    """The largest acceleration (mm/s^2) whose smoothing stays within target (0 if the corner
    velocity alone exceeds it; unbounded for a single impulse, which never smooths)."""
    c90, k90, k180 = _offsets(amps, times_s, scv)
    if c90 > target:
        return 0.0
    return min((target - c90) / k90 if k90 > 0 else math.inf, target / k180 if k180 > 0 else math.inf)


def figures(kind: str, f_hz: float, zeta: float = DEFAULT_ZETA, freqs=None, psd=None,
            resonance: tuple[float, float] | None = None) -> dict:
    """Klipper's figures of the shaper kind designed at (f_hz, zeta): its remaining vibration on
    the normalised PSD (freqs, psd), or without one on the modelled axis resonance (f, zeta)
    (default: the shaper's own), its smoothing (mm) and the max acceleration (mm/s^2)."""
    sh = design(kind, f_hz, zeta)
    if psd is None:
        freqs, psd = mode_psd(*(resonance or (f_hz, zeta)))
    vib, _ = remaining_vibrations(sh.amps, sh.times_s, np.asarray(freqs, float), np.asarray(psd, float))
    return {"type": kind, "freq_hz": float(f_hz), "damping_ratio": float(zeta), "vibration": vib,
            "smoothing_mm": smoothing(sh.amps, sh.times_s), "max_accel_mm_s2": max_accel(sh.amps, sh.times_s)}


def describe(fig: dict) -> str:
    """One line: 'mzv 40.0 Hz (damping 0.1): vibration 3.1 %, smoothing 0.052 mm, max accel 5,400 mm/s^2'."""
    return (f"{fig['type']} {fig['freq_hz']:.1f} Hz (damping {fig['damping_ratio']:g}): vibration "
            f"{100 * fig['vibration']:.1f} %, smoothing {fig['smoothing_mm']:.3f} mm, max accel "
            f"{round(fig['max_accel_mm_s2'] / 100) * 100:,.0f} mm/s^2")


def axis_figures(designs, dynamics: dict | None = None) -> list[dict]:
    """figures() of each shaped axis of a machine's designs ((kind, f_hz, zeta) per axis), with
    "axis"; the vibration on the axis's [dynamics] resonance when given, else on the shaper's own."""
    out = []
    for i, (kind, f, z) in enumerate(designs):
        if kind != "none":
            res = (dynamics["f_hz"][i], dynamics["zeta"][i]) if dynamics else None
            out.append({"axis": "xy"[i], **figures(kind, f, z, resonance=res)})
    return out
