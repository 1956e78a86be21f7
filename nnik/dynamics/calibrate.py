"""Input shaper calibration from a resonance test log: the power spectral density, the axis's
resonance (frequency and damping) and the shaper Klipper's rules recommend.

PSD: Welch's method as Klipper's shaper_calibrate computes it (a Kaiser window, beta 6, of the
power of two at or above 0.5 s of samples, half overlapping, each window's mean removed, density
scaling), per accelerometer axis and their sum.

Resonance: the test drives the axis with acceleration amplitude proportional to f at a constant
sweep rate, so the measured PSD is c f^2 |H(f)|^2 plus the accelerometer's white noise n, with
H the base-excited spring-damper's (nnik.dynamics.axis; base to tip acceleration).  The peak of
PSD / f^2 and its half-power points give a first (f, zeta); a least-squares fit of that model,
smeared by the Welch window's own spectrum (and the bit of sweep each window holds), in log
power over the peak's neighbourhood gives the undamped natural frequency f_n and the damping
ratio.  The fit stops short of where the sweep ended: from a raw log, the drive's highest
frequency (sweep_end); from a processed one, where the PSD steps down END_DROP times within two
bins (to the drive's harmonics, ~1/243) and stays there, two bins or more past the peak.

Shaper: Klipper's fit_shaper and find_best_shaper rules, restated: each shaper's frequency is
scanned down from 200 Hz in 0.2 Hz steps from its min_freq; its vibration (the worst over damping
0.075, 0.1, 0.15), smoothing and score smoothing (v^1.5 + 0.2 v + 0.01) are kept; the least
vibration wins, then the lowest-score frequency whose vibration is within 1.1 x + 0.0005 of it is
taken.  Across shapers (zv, mzv, ei, 2hump_ei, 3hump_ei) a later one replaces the pick if its
score is 20 % lower, or 5 % lower with 10 % less smoothing; any result with both less vibration
and less smoothing replaces it; a zv pick gives way to the first shaper with 10 % less vibration.
ZVD is fitted and shown as well, but not picked (Klipper leaves it out of its autotune list).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import get_window, welch

from nnik.dynamics.shaper_figures import (DEFAULT_ZETA, MAX_FREQ, MIN_FREQ, max_accel, mode_gain2, normalize_psd,
                                          remaining_vibrations, smoothing)
from nnik.dynamics.shapers import KINDS, design

WINDOW_S = 0.5  # Klipper's Welch window
SWEEP_HZ_PER_S = 1.0  # Klipper's default hz_per_sec: a window's chirp widens its kernel by this x its length
# where the sweep ends the drive stops: the PSD falls this much within two bins (to the square
# wave's harmonics, ~1/243 of it), which no resonance's flank does 3 half-widths past its peak
END_DROP = 12.0
INTERIOR_DROP = 1.1
KAISER_BETA = 6.0
MIN_SHAPER_FREQ = {"zv": 21.0, "mzv": 23.0, "zvd": 29.0, "ei": 29.0, "2hump_ei": 39.0, "3hump_ei": 48.0}
AUTOTUNE = ("zv", "mzv", "ei", "2hump_ei", "3hump_ei")
FREQ_STEP = 0.2
SEARCH_LO_HZ = 1.5 * MIN_FREQ  # the resonance is sought from here (below, the sweep has not begun)
KERNEL_OVERSAMPLE, KERNEL_BINS = 8, 8
PSD_NFFT = 2048  # a processed log's window (Klipper's at 3200 Hz; the kernel's shape in bins hardly depends on it)


class CalibrationError(ValueError):
    """A log that cannot give a resonance: one line."""


@dataclass
class Spectrum:
    freqs: np.ndarray
    psd: np.ndarray  # (N, 4): x, y, z and their sum, not normalised
    nfft: int  # the Welch window behind the bins (0: unknown)
    rate_hz: float = 0.0
    sweep_end_hz: float | None = None  # where the test's drive stopped, when the log tells (raw)


def sweep_end(rows: np.ndarray, m: int, fs: float) -> float | None:
    """The highest frequency the test drove: in each window the drive stands out as one tone (the
    axis answers at the frequency it is driven at); the 99th percentile of the tones' frequencies
    over the windows that have one (its bin 20 x the window's median)."""
    n = (len(rows) // m) * m
    if n < 4 * m:
        return None
    x = rows[:n, 1:4].reshape(-1, m, 3)
    x = x - x.mean(axis=1, keepdims=True)
    spec = (np.abs(np.fft.rfft(x, axis=1)) ** 2).sum(axis=2)
    freqs = np.fft.rfftfreq(m, 1.0 / fs)
    band = (freqs >= MIN_FREQ) & (freqs <= 0.45 * fs)
    s = spec[:, band]
    tonal = s.max(axis=1) > 20 * np.median(s, axis=1)
    if tonal.sum() < 4:
        return None
    return float(np.percentile(freqs[band][np.argmax(s[tonal], axis=1)], 99))


def _welch(rows: np.ndarray, window_s: float) -> Spectrum:
    t = rows[:, 0]
    fs = (len(t) - 1) / (t[-1] - t[0])
    m = 1 << int(fs * window_s - 1).bit_length()
    if len(t) <= m:
        raise CalibrationError(f"too short: {t[-1] - t[0]:.2f} s of samples; the PSD needs more than {m} samples "
                               f"({m / fs:.2f} s) at {fs:.0f} Hz")
    cols = []
    for k in (1, 2, 3):
        freqs, p = welch(rows[:, k], fs=fs, window=("kaiser", KAISER_BETA), nperseg=m, noverlap=m // 2,
                         detrend="constant", scaling="density")
        cols.append(p)
    psd = np.column_stack(cols + [cols[0] + cols[1] + cols[2]])
    return Spectrum(freqs, psd, m, fs, sweep_end(rows, m, fs))


def klipper_spectrum(rows: np.ndarray) -> Spectrum:
    """Klipper's PSD of raw rows (time, ax, ay, az)."""
    return _welch(rows, WINDOW_S)


def _kernel(nfft: int, chirp_bins: float) -> np.ndarray:
    """The Kaiser window's power spectrum on a grid KERNEL_OVERSAMPLE times finer than the bins,
    over +-KERNEL_BINS bins, widened by the chirp a window holds (a box chirp_bins wide), summing
    to 1."""
    w = get_window(("kaiser", KAISER_BETA), nfft, fftbins=True)
    spec = np.abs(np.fft.fft(w, nfft * KERNEL_OVERSAMPLE)) ** 2
    half = KERNEL_BINS * KERNEL_OVERSAMPLE
    k = np.concatenate([spec[-half:], spec[:half + 1]])
    box = max(1, int(round(chirp_bins * KERNEL_OVERSAMPLE)))
    k = np.convolve(k, np.ones(box), mode="same")
    return k / k.sum()


def _smooth(q: np.ndarray, n: int) -> np.ndarray:
    return np.convolve(q, np.ones(n) / n, mode="same") if n > 1 else q


def _half_power(f: np.ndarray, q: np.ndarray, i: int) -> tuple[int | None, int | None]:
    """Indices where q first falls below half of q[i] on either side (None: it never does)."""
    half = q[i] / 2
    left = np.flatnonzero(q[:i] < half)
    right = np.flatnonzero(q[i + 1:] < half)
    return (int(left[-1]) if len(left) else None), (int(right[0]) + i + 1 if len(right) else None)


@dataclass
class Resonance:
    f_hz: float
    zeta: float
    peak_hz: float
    band: tuple[float, float]  # the fitted bins' range
    fitted: dict = field(default_factory=dict)


def find_resonance(sp: Spectrum, hi_hz: float | None = None) -> Resonance:
    """The dominant resonance in [SEARCH_LO_HZ, hi_hz (default MAX_FREQ, and below Nyquist)] of
    the summed PSD.  CalibrationError when there is none."""
    f, p = sp.freqs, sp.psd[:, 3]
    df = float(f[-1] - f[0]) / (len(f) - 1)
    # a bin below the sweep's end: past it the drive is gone
    hi = min(hi_hz or MAX_FREQ, MAX_FREQ, (sp.rate_hz or np.inf) * 0.45, (sp.sweep_end_hz or np.inf) - df)
    sel = (f >= SEARCH_LO_HZ) & (f <= hi)
    if sel.sum() < 8:
        raise CalibrationError(f"no resonance in {SEARCH_LO_HZ:g}-{hi:g} Hz: the log has {int(sel.sum())} bins there")
    # the response with the test's f^2 drive taken out, over ~1.5 Hz (a window's ripple averaged)
    fs, q = f[sel], _smooth(p[sel] / f[sel] ** 2, int(round(1.5 / df)))
    if not np.all(np.isfinite(q)) or q.max() <= 0:
        raise CalibrationError(f"no resonance in {SEARCH_LO_HZ:g}-{hi:g} Hz: the PSD is zero there")
    i = int(np.argmax(q))
    lo_i, hi_i = _half_power(fs, q, i)
    # a peak near the band's (or the sweep's) end may fall to half power on one side only; the
    # other side must still fall by a tenth: a response that keeps rising is no resonance
    interior = 2 <= i <= len(q) - 3 and q[i] > INTERIOR_DROP * max(q[0], q[-1])
    if (lo_i is None and hi_i is None) or ((lo_i is None or hi_i is None) and not interior):
        where = "the band's lower end" if lo_i is None else "the band's upper end"
        raise CalibrationError(f"no resonance in {SEARCH_LO_HZ:g}-{hi:g} Hz: the response has no peak that falls to half "
                               f"its power (it keeps rising towards {where})")
    fp = float(fs[i])
    half_widths = [fp - fs[lo_i]] if lo_i is not None else []
    half_widths += [fs[hi_i] - fp] if hi_i is not None else []
    z0 = float(np.clip(np.mean(half_widths) / fp, 0.01, 0.5))
    w = float(np.clip(3 * z0, 0.12, 0.35))
    band = (max(fp * (1 - w), SEARCH_LO_HZ), min(fp * (1 + w), hi))
    if sp.sweep_end_hz is None:  # a PSD without times: the sweep's end is where the power steps down
        start = int(np.searchsorted(f, fp)) + 2
        for k in range(start, min(int(np.searchsorted(f, band[1])), len(f) - 3)):
            if p[k - 1] > END_DROP * p[k + 1] and p[k + 1] < 3 * p[k + 3]:  # a step, flat after it
                band = (band[0], float(f[k - 1]))
                break
    res = _fit(sp, band, fp, z0)
    if not (band[0] <= res.f_hz <= band[1]) or not 0.0 < res.zeta <= 0.5:
        raise CalibrationError(f"no resonance in {SEARCH_LO_HZ:g}-{hi:g} Hz: the spring-damper fit around {fp:.1f} Hz "
                               f"does not hold (f {res.f_hz:.1f} Hz, damping {res.zeta:.3f})")
    return res


def _fit(sp: Spectrum, band: tuple[float, float], fp: float, z0: float) -> Resonance:
    f, p = sp.freqs, sp.psd[:, 3]
    df = float(f[-1] - f[0]) / (len(f) - 1)
    sel = np.flatnonzero((f >= band[0]) & (f <= band[1]))
    # a window of 1 / df seconds holds SWEEP_HZ_PER_S / df Hz of the sweep
    kern = _kernel(sp.nfft, SWEEP_HZ_PER_S / df**2) if sp.nfft else np.array([1.0])
    over = KERNEL_OVERSAMPLE if sp.nfft else 1
    half = (len(kern) - 1) // 2
    fine = f[sel[0]] + (np.arange((len(sel) - 1) * over + 1 + 2 * half) - half) * df / over
    fine = np.maximum(fine, 1e-3)
    at = np.arange(len(sel)) * over  # the bins on the convolved grid
    y = np.log(np.maximum(p[sel], 1e-300))

    def model(x):
        fn, z, c, n = np.exp(x)
        m = np.convolve(c * fine**2 * mode_gain2(fine, fn, z), kern, mode="valid")
        return m[at] + n

    g0 = mode_gain2(np.array([fp]), fp, z0)[0]
    c0 = float(np.max(p[sel]) / (fp**2 * g0))
    # the noise floor: under the band's lowest power
    n0 = max(float(np.min(p[sel])) * 0.1, 1e-30)
    x0 = np.log([fp, z0, c0, n0])
    lo = np.log([band[0], 0.003, c0 * 1e-4, n0 * 1e-6])
    hi = np.log([band[1], 0.9, c0 * 1e4, n0 * 10])
    sol = least_squares(lambda x: np.log(np.maximum(model(x), 1e-300)) - y, np.clip(x0, lo + 1e-9, hi - 1e-9),
                        bounds=(lo, hi), x_scale="jac")
    fn, z, c, n = np.exp(sol.x)
    return Resonance(float(fn), float(z), fp, (float(f[sel[0]]), float(f[sel[-1]])),
                     {"scale": float(c), "noise": float(n), "rms_log": float(np.sqrt(np.mean(sol.fun**2)))})


@dataclass
class ShaperFit:
    kind: str
    freq_hz: float
    vibration: float
    smoothing_mm: float
    max_accel_mm_s2: float
    score: float
    vals: np.ndarray  # the shaper's worst response on the PSD's bins


def fit_shaper(kind: str, freqs: np.ndarray, psd_norm: np.ndarray, zeta: float = DEFAULT_ZETA) -> tuple[ShaperFit, list]:
    """(the pick, every scanned frequency's ShaperFit, highest first) of one shaper kind on a
    normalised PSD, by Klipper's rule."""
    keep = freqs <= MAX_FREQ
    freqs, psd = freqs[keep], psd_norm[keep]
    test = np.arange(MIN_SHAPER_FREQ[kind], MAX_FREQ, FREQ_STEP)
    results, best = [], None
    for f in test[::-1]:
        sh = design(kind, float(f), zeta)
        sm = smoothing(sh.amps, sh.times_s)
        vib, vals = remaining_vibrations(sh.amps, sh.times_s, freqs, psd)
        r = ShaperFit(kind, float(f), vib, sm, max_accel(sh.amps, sh.times_s), sm * (vib**1.5 + vib * 0.2 + 0.01), vals)
        results.append(r)
        if best is None or best.vibration > r.vibration:
            best = r
    pick = best
    for r in results[::-1]:
        if r.vibration < best.vibration * 1.1 + 0.0005 and r.score < pick.score:
            pick = r
    return pick, results


def best_shaper(freqs: np.ndarray, psd_norm: np.ndarray, zeta: float = DEFAULT_ZETA) -> tuple[ShaperFit, dict]:
    """(Klipper's recommendation, {kind: its fitted ShaperFit} for every kind)."""
    fits, best = {}, None
    for kind in AUTOTUNE:
        pick, results = fit_shaper(kind, freqs, psd_norm, zeta)
        if (best is None or pick.score * 1.2 < best.score
                or (pick.score * 1.05 < best.score and pick.smoothing_mm * 1.1 < best.smoothing_mm)):
            best = pick
        for r in results[::-1]:
            if r.vibration < best.vibration and r.smoothing_mm < best.smoothing_mm:
                best = pick = r
        fits[kind] = pick
    if best.kind == "zv":
        for kind in AUTOTUNE:
            if kind != "zv" and fits[kind].vibration * 1.1 < best.vibration:
                best = fits[kind]
                break
    fits["zvd"] = fit_shaper("zvd", freqs, psd_norm, zeta)[0]
    return best, {k: fits[k] for k in KINDS}
