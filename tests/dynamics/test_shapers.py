"""Input shapers: the textbook properties, at random resonances (not only the shipped 40 Hz)."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.dynamics.shapers import KINDS, MAX_ZETA, design, quantize, quantized_residual, residual

freqs = st.floats(5.0, 200.0)
fractions = st.floats(0.0, 1.0)  # of the kind's largest damping ratio


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(KINDS), f=freqs, u=fractions)
def test_impulses_are_a_unit_train_over_the_stated_duration(kind, f, u):
    zeta = u * MAX_ZETA[kind]
    sh = design(kind, f, zeta)
    assert math.isclose(sum(sh.amps), 1.0, rel_tol=1e-12) and min(sh.amps) > 0
    assert sh.times_s[0] == 0 and list(sh.times_s) == sorted(sh.times_s)
    t_d = 1 / (f * math.sqrt(1 - zeta**2))
    if kind.endswith("hump_ei"):  # 1.5 and 2 periods (1 / f), the fit's times moving a little with zeta
        assert abs(sh.duration_s * f - {"2hump_ei": 1.5, "3hump_ei": 2.0}[kind]) < 0.1
    else:
        assert math.isclose(sh.duration_s, {"zv": 0.5, "mzv": 0.75, "zvd": 1.0, "ei": 1.0}[kind] * t_d, rel_tol=1e-9)


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(KINDS), f=freqs, u=fractions)
def test_residual_vibration_at_the_design_frequency(kind, f, u):
    zeta = u * MAX_ZETA[kind]
    sh = design(kind, f, zeta)
    r = residual(sh.amps, sh.times_s, f, zeta)
    if kind in ("ei", "3hump_ei"):  # 5 % allowed at f (a hump) to widen the band
        assert 0.04 < r < 0.055
    elif kind == "2hump_ei":  # its two humps sit either side of f
        assert r < 0.005
    else:
        assert r < 1e-9
    assert residual([1.0], [0.0], f, zeta) == pytest.approx(1.0)


@pytest.mark.parametrize("kind", [k for k in KINDS if k.endswith("ei")])
def test_ei_shapers_hold_vibration_near_5_percent_over_a_wide_band(kind):
    """EI: +-20 %; 2HUMP_EI +-38 %, 3HUMP_EI +-45 % of f at most ~5.5 % (the humps), at zeta 0.1."""
    half = {"ei": 0.2, "2hump_ei": 0.38, "3hump_ei": 0.45}[kind]
    sh = design(kind, 50, 0.1)
    worst = max(residual(sh.amps, sh.times_s, 50 * (1 + half * k / 50), 0.1) for k in range(-50, 51))
    assert worst < 0.056


def test_damping_above_klippers_limit_is_refused():
    for kind, z in MAX_ZETA.items():
        design(kind, 40, z)
        with pytest.raises(ValueError, match="Klipper's limit"):
            design(kind, 40, min(z + 0.01, 0.999))


def test_robustness_to_a_wrong_frequency_matches_the_published_ranking():
    # at 50 Hz, zeta 0.1, true frequency off by +/-20 %: ZV 25-27 %, MZV 11-19 %, ZVD 6-7 %, EI 2-2.4 %
    # (DOMAIN.md, Klipper's figures)
    want = {"zv": (0.24, 0.28), "mzv": (0.10, 0.20), "zvd": (0.055, 0.075), "ei": (0.018, 0.026)}
    for kind, (lo, hi) in want.items():
        sh = design(kind, 50, 0.1)
        for f in (40, 60):
            assert lo <= residual(sh.amps, sh.times_s, f, 0.1) <= hi, (kind, f)


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(KINDS), f=st.floats(5.0, 250.0), u=fractions, fs=st.sampled_from([500, 1000, 2000]))
def test_fixed_point_taps_sum_to_one_and_keep_the_notch(kind, f, u, fs):
    zeta = u * min(MAX_ZETA[kind], 0.5)  # (at zeta 0.99 a ZV's second impulse is below one Q15 step)
    if f > fs / 4:
        return
    sh = design(kind, f, zeta)
    amps, delays = quantize(sh, fs)
    assert sum(amps) == 1 << 15 and all(a > 0 for a in amps)
    assert delays == sorted(set(delays)) and delays[0] == 0
    assert delays[-1] <= math.ceil(sh.duration_s * fs)
    # splitting an impulse between two samples keeps the residual near the design's
    ideal = residual(sh.amps, sh.times_s, f, zeta)
    # (linear interpolation of a delay errs by about (pi f / fs)^2 / 4 on a sinusoid)
    assert quantized_residual(sh, fs) <= ideal + 0.005 + (math.pi * f / fs) ** 2 / 4


@pytest.mark.parametrize("bad", [("zv", 40, 1.0), ("zvd", 0, 0.1), ("ei", float("nan"), 0.1), ("foo", 40, 0.1)])
def test_bad_designs_are_refused(bad):
    with pytest.raises(ValueError):
        design(*bad)
