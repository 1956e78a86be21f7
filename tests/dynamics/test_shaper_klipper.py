"""The shapers against Klipper's published definitions, and Klipper's three figures per shaper.

Reference: Klipper's klippy/extras/shaper_defs.py (Klipper3d/klipper, commit 84104bb, 2026-08;
the *EI definitions of commit 5da026a "Updated definitions of *EI input shapers" and the
3HUMP_EI comma fix 0d1445a) and klippy/extras/shaper_calibrate.py (_get_shaper_smoothing,
find_shaper_max_accel, _estimate_remaining_vibrations).  The formulas are written out again
below, independently of nnik.dynamics.shapers, as a test table; amplitudes compare in Q15 (within
one step of rounding) and times to a nanosecond.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nnik.dynamics.shaper_figures import figures, max_accel, mode_psd, remaining_vibrations, smoothing
from nnik.dynamics.shapers import KINDS, design


def _poly(c, z):  # c0 + c1 z + c2 z^2 + c3 z^3
    return sum(ci * z**i for i, ci in enumerate(c))


def klipper_reference(kind: str, f: float, z: float) -> tuple[list[float], list[float]]:
    """(A, T) as shaper_defs.py publishes them (A not normalised)."""
    df = math.sqrt(1 - z * z)
    td = 1 / (f * df)
    if kind == "zv":
        k = math.exp(-z * math.pi / df)
        return [1, k], [0, td / 2]
    if kind == "zvd":
        k = math.exp(-z * math.pi / df)
        return [1, 2 * k, k * k], [0, td / 2, td]
    if kind == "mzv":  # n = 3 impulses over t = 0.75 damped periods
        k = math.exp(-0.75 * z * math.pi / df)
        a1 = 1 - 1 / math.sqrt(2)
        return [a1, (math.sqrt(2) - 1) * k, a1 * k * k], [0, 0.375 * td, 0.75 * td]
    if kind == "ei":
        v = 1 / 20  # 1 / SHAPER_VIBRATION_REDUCTION
        a1 = _poly([0.24968 + 0.24961 * v, 0.80008 + 1.23328 * v, 0.49599 + 3.17316 * v], z)
        a3 = _poly([0.25149 + 0.21474 * v, -0.83249 + 1.41498 * v, 0.85181 - 4.90094 * v], z)
        t2 = _poly([0.4999, (0.46159 + 8.57843 * v) * v, (4.26169 - 108.644 * v) * v, (1.75601 + 336.989 * v) * v], z)
        return [a1, 1 - a1 - a3, a3], [0, t2 * td, td]
    tab = {  # (t rows, a rows): each a cubic in z; times in units of 1 / f
        "2hump_ei": ([[0, 0, 0, 0], [0.49890, 0.16270, -0.54262, 6.16180], [0.99748, 0.18382, -1.58270, 8.17120],
                      [1.49920, -0.09297, -0.28338, 1.85710]],
                     [[0.16054, 0.76699, 2.26560, -1.22750], [0.33911, 0.45081, -2.58080, 1.73650],
                      [0.34089, -0.61533, -0.68765, 0.42261], [0.15997, -0.60246, 1.00280, -0.93145]]),
        "3hump_ei": ([[0, 0, 0, 0], [0.49974, 0.23834, 0.44559, 12.4720], [0.99849, 0.29808, -2.36460, 23.3990],
                      [1.49870, 0.10306, -2.01390, 17.0320], [1.99960, -0.28231, 0.61536, 5.40450]],
                     [[0.11275, 0.76632, 3.29160, -1.44380], [0.23698, 0.61164, -2.57850, 4.85220],
                      [0.30008, -0.19062, -2.14560, 0.13744], [0.23775, -0.73297, 0.46885, -2.08650],
                      [0.11244, -0.45439, 0.96382, -1.46000]]),
    }[kind]
    return [_poly(c, z) for c in tab[1]], [_poly(c, z) / f for c in tab[0]]


POINTS = [(25.0, 0.05), (40.0, 0.1), (70.0, 0.2), (110.0, 0.0)]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("f,zeta", POINTS)
def test_coefficients_match_klippers_published_definitions_to_q15(kind, f, zeta):
    a_ref, t_ref = klipper_reference(kind, f, zeta)
    sh = design(kind, f, zeta)
    q_ref = [round(a / sum(a_ref) * 32768) for a in a_ref]
    q_got = [round(a * 32768) for a in sh.amps]
    assert len(q_got) == len(q_ref) and max(abs(a - b) for a, b in zip(q_got, q_ref)) <= 1, (q_got, q_ref)
    assert max(abs(a - b) for a, b in zip(sh.times_s, t_ref)) < 1e-9


# Q15 amplitudes and times (us) at 40 Hz, zeta 0.1, from the formulas above (worked out once)
PINNED = {"zv": ([18949, 13819], [0.0, 12563.0]), "mzv": ([11965, 13353, 7451], [0.0, 9422.2, 18844.5]),
          "zvd": ([10958, 15982, 5828], [0.0, 12563.0, 25125.9]), "ei": ([11629, 14844, 6295], [0.0, 12681.0, 25125.9]),
          "2hump_ei": ([8472, 11794, 8938, 3564], [0.0, 12897.6, 25205.2, 37223.2]),
          "3hump_ei": ([7237, 9084, 8510, 5474, 2463], [0.0, 13512.5, 25701.3, 37647.5, 49573.2])}


@pytest.mark.parametrize("kind", KINDS)
def test_pinned_values_at_40_hz(kind):
    sh = design(kind, 40.0, 0.1)
    amps, times = PINNED[kind]
    assert [round(a * 32768) for a in sh.amps] == amps
    assert [round(t * 1e6, 1) for t in sh.times_s] == times


def test_smoothing_and_max_accel_match_klippers_published_example():
    """docs/Measuring_Resonances.md prints, for ZV at 34.4 Hz: smoothing ~= 0.132, max_accel <=
    4500; for MZV at 34.6 Hz: 0.170 and 3500 (scv 5 mm/s, damping 0.1; max_accel rounded to 100).
    (Its EI-family lines predate the 2024 EI definitions, so they are not compared.)"""
    for kind, f, sm, acc in (("zv", 34.4, 0.132, 4500), ("mzv", 34.6, 0.170, 3500)):
        fig = figures(kind, f, 0.1)
        assert round(fig["smoothing_mm"], 3) == sm
        assert round(fig["max_accel_mm_s2"] / 100) * 100 == acc


def _smoothing_by_definition(a, t, accel, scv):
    """_get_shaper_smoothing restated: the 90 and 180 degree offsets around the shaper's shift."""
    a = np.asarray(a) / np.sum(a)
    t = np.asarray(t)
    ts = float(np.sum(a * t))
    o90 = sum(ai * (scv + accel / 2 * (ti - ts)) * (ti - ts) for ai, ti in zip(a, t) if ti >= ts) * math.sqrt(2)
    o180 = sum(ai * accel / 2 * (ti - ts) ** 2 for ai, ti in zip(a, t))
    return max(o90, o180)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("f,zeta", POINTS)
def test_max_accel_is_where_the_smoothing_reaches_0_12_mm(kind, f, zeta):
    a, t = klipper_reference(kind, f, zeta)
    acc = max_accel(a, t)
    assert smoothing(a, t) == pytest.approx(_smoothing_by_definition(a, t, 5000, 5.0), rel=1e-12)
    assert _smoothing_by_definition(a, t, acc, 5.0) == pytest.approx(0.12, rel=1e-9)
    assert _smoothing_by_definition(a, t, acc * 1.001, 5.0) > 0.12


def test_remaining_vibrations_by_definition():
    """On a PSD: sum(max(vals * psd - max(psd) / 20, 0)) / sum(max(psd - max(psd) / 20, 0)), the
    worst over damping ratios 0.075, 0.1, 0.15; a flat response (no shaper) leaves all of it."""
    freqs, psd = mode_psd(45.0, 0.08)
    v_none, vals = remaining_vibrations([1.0], [0.0], freqs, psd)
    assert v_none == pytest.approx(1.0) and np.allclose(vals, 1.0)
    sh = design("zv", 38.0, 0.1)  # tuned 16 % low: some vibration remains
    v, _ = remaining_vibrations(sh.amps, sh.times_s, freqs, psd)
    want = 0.0
    for z in (0.075, 0.1, 0.15):
        w = 2 * np.pi * freqs
        wd = w * math.sqrt(1 - z * z)
        a, t = np.array(sh.amps), np.array(sh.times_s)
        e = a * np.exp(-np.outer(z * w, t[-1] - t))
        r = np.hypot((e * np.sin(np.outer(wd, t))).sum(1), (e * np.cos(np.outer(wd, t))).sum(1))
        floor = psd.max() / 20
        want = max(want, np.maximum(r * psd - floor, 0).sum() / np.maximum(psd - floor, 0).sum())
    assert v == pytest.approx(want, rel=1e-12) and 0.01 < v < 0.5


def test_longer_shapers_smooth_more_and_allow_less_acceleration():
    figs = [figures(k, 50.0, 0.1) for k in ("zv", "mzv", "zvd", "2hump_ei", "3hump_ei")]
    sm = [f["smoothing_mm"] for f in figs]
    acc = [f["max_accel_mm_s2"] for f in figs]
    assert sm == sorted(sm) and acc == sorted(acc, reverse=True)
