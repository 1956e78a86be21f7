"""`nnik shaper-calibrate`'s analysis of one log (nnik.dynamics.resonance_log): its spectra, the
resonance (nnik.dynamics.calibrate.find_resonance) and every shaper fitted by Klipper's rules."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nnik.dynamics.calibrate import (PSD_NFFT, Resonance, ShaperFit, Spectrum, best_shaper, find_resonance,
                                     klipper_spectrum)
from nnik.dynamics.resonance_log import ResonanceLog
from nnik.dynamics.shaper_figures import DEFAULT_ZETA, denormalize_psd, normalize_psd


@dataclass
class Calibration:
    spectrum: Spectrum  # Klipper's bins, not normalised
    psd_norm: np.ndarray  # the summed PSD, normalised as Klipper fits shapers to it
    resonance: Resonance
    best: ShaperFit
    fits: dict  # kind -> ShaperFit
    zeta: float  # the damping ratio the shapers are designed for


def spectrum_of(log: ResonanceLog) -> Spectrum:
    """Klipper's spectrum of a log (a processed one: its normalisation undone)."""
    if log.kind == "raw":
        return klipper_spectrum(log.rows)
    f, psd = log.rows[:, 0], log.rows[:, 1:5]
    if log.normalized:
        psd = np.column_stack([denormalize_psd(f, psd[:, k]) for k in range(4)])
    return Spectrum(f, psd, PSD_NFFT)


def calibrate(log: ResonanceLog, zeta: float = DEFAULT_ZETA) -> Calibration:
    sp = spectrum_of(log)
    res = find_resonance(sp)
    norm = normalize_psd(sp.freqs, sp.psd[:, 3])
    best, fits = best_shaper(sp.freqs, norm, zeta)
    return Calibration(sp, norm, res, best, fits, zeta)
