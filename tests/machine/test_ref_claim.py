"""The pieces of a measured machine's claim (nnik.machine.ref_claim), on fields whose answer is
known: the deconvolution of rounding noise, the correlation length of the residuals, and how an
implementation's error field combines with the reference's."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.machine import ref_claim
from nnik.machine.reference import Noise


def test_deconvolution_finds_the_amplitude_under_rounding_noise():
    rng = np.random.default_rng(0)
    amp = 0.3
    u = amp * np.sin(rng.uniform(0, 2 * np.pi, 4000))  # an arcsine distribution, bounded by amp
    r = u + rng.uniform(-0.5, 0.5, u.size)
    atoms, w = ref_claim.deconvolve(r, 1.0, np.full(r.size, 1e-3))
    assert w.sum() == pytest.approx(1.0)
    cdf = np.cumsum(w)
    hi = atoms[np.searchsorted(cdf, 0.995)]
    assert 0.8 * amp <= hi <= 1.25 * amp  # while max |r| is near amp + 0.5
    assert np.abs(r).max() > amp + 0.4


def test_correlation_length_of_a_smooth_field():
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 100, (600, 2))
    ell = 20.0
    # a smooth field sampled at the marks plus independent noise (the pairs' products drop it)
    k = rng.normal(size=(40, 2)) / ell
    ph = rng.uniform(0, 2 * np.pi, 40)
    field = np.sqrt(2 / 40) * np.cos(p @ k.T + ph).sum(1)
    r = np.stack([field, field], 1) * 0.2 + rng.normal(0, 0.3, (600, 2))
    got = ref_claim.correlation_length(p, r, np.array([0.04, 0.04]), float(np.hypot(100, 100)))
    assert 0.5 * ell <= got <= 2 * ell


def _fields(value: np.ndarray) -> ref_claim.ErrorFields:
    g = 9
    f = np.broadcast_to(value[:, None, None, :], (len(value), g, g, 2)).astype(np.float32).copy()
    return ref_claim.ErrorFields(np.zeros(2), np.ones(2), f, np.ones((g, g), bool), "test")


def test_the_claim_follows_the_alignment_not_the_sum_of_maxima():
    # replicates: the reference is off by +-0.2 everywhere, half the replicates each way
    ef = _fields(np.array([[0.2, 0.2]] * 10 + [[-0.2, -0.2]] * 10))
    p = np.random.default_rng(2).uniform(0, 1, (500, 2))
    d = np.zeros((500, 2))
    d[0] = [0.5, 0.0]  # the implementation's peak
    assert ef.claim(p, d) == pytest.approx(0.7)  # the LEVEL quantile: some replicate adds at the peak
    d[1] = [-0.5, 0.0]  # a peak of each sign: every replicate adds at one of them
    assert ef.claim(p, d) == pytest.approx(0.7)
    assert ef.floors() == pytest.approx([0.2, 0.2])
    ef0 = _fields(np.zeros((20, 2)))
    assert ef0.claim(p, d) == pytest.approx(0.5)  # an exact reference: the implementation's own max


def test_noise_draws_follow_the_model():
    rng = np.random.default_rng(3)
    rounding = Noise(np.full(2, 1 / 12), np.full(2, 0.5), "rounded", 1.0)
    n = ref_claim.draw_noise(rng, rounding, 20000)
    assert np.abs(n).max() <= 0.5 and n.var() == pytest.approx(1 / 12, rel=0.05)
    gauss = Noise(np.full(2, 0.04), np.full(2, 0.6), "position")
    g = ref_claim.draw_noise(rng, gauss, 20000)
    assert g.std() == pytest.approx(0.2, rel=0.05) and np.abs(g).max() > 0.6


def test_a_reference_that_cannot_be_refitted_borrows_the_best_refit():
    from nnik.machine.reference import fit_reference, known_noise

    rng = np.random.default_rng(4)
    p = rng.uniform(0, 100, (120, 2))

    def truth(pm):
        return np.stack([3 * pm[:, 0] + 0.002 * pm[:, 1] ** 2, pm[:, 0] - 2 * pm[:, 1] + 0.3 * np.sin(pm[:, 0] / 9)], 1)
    q = np.rint(truth(p))
    noise = known_noise(q, np.eye(2), reading_step=1.0)
    held = rng.uniform(0, 100, (40, 2))
    ref = fit_reference(p, q, noise, extra={"mlp": (truth, held, truth(held) - np.rint(truth(held)))}, gp=False)
    assert ref.name == "mlp"  # the outside model scored best (it is the truth)
    assert "(for mlp)" in ref.fields.method and ref.fields.fields.shape[0] == ref_claim.BOOT
    assert 0 < ref.error_max < 1.0


def test_the_claim_equals_the_brute_force_over_every_point():
    rng = np.random.default_rng(5)
    g = 17
    f = rng.normal(0, 0.1, (12, g, g, 2)).astype(np.float32)
    ef = ref_claim.ErrorFields(np.zeros(2), np.full(2, 10.0), f, np.ones((g, g), bool), "test")
    p = rng.uniform(0, 10, (30000, 2))
    d = 0.05 * np.sin(p[:, :1] * 3 + np.array([0.0, 1.0])) + rng.normal(0, 0.01, (30000, 2))
    cells = ef._cells(p)
    brute = [float(np.abs(d + ef.at(b, p, cells)).max()) for b in range(12)]
    assert ef.claim(p, d) == pytest.approx(float(np.quantile(brute, ref_claim.LEVEL)))


def test_an_outside_winner_keeps_each_residual_with_its_own_mark():
    """issue 25: the MLP scored on fewer held-out rows than there are marks wins the CV while
    its residuals hold a correlated error; the unresolved part pairs each residual with the mark
    it was measured at (it was paired with all the marks and crashed)."""
    from nnik.machine.reference import fit_reference, known_noise

    rng = np.random.default_rng(6)
    p = rng.uniform(0, 100, (160, 2))

    def truth(pm):
        return np.stack([3 * pm[:, 0] + 2 * np.sin(pm[:, 1] / 3), pm[:, 0] - 2 * pm[:, 1] + 2 * np.cos(pm[:, 0] / 3)], 1)

    def mlp(pm):  # close to the truth, off by a smooth bias of 0.4 units
        return truth(pm) + 0.4 * np.sin(pm / 30.0)
    q = np.rint(truth(p))
    noise = known_noise(q, np.eye(2), reading_step=1.0)
    held = p[:40]  # the MLP's held-out rows are a quarter of the marks
    ref = fit_reference(p, q, noise, extra={"mlp": (mlp, held, mlp(held) - q[:40])}, gp=False)
    assert ref.name == "mlp"
    assert "correlation length" in ref.fields.method  # the unresolved error was added
    assert np.all(np.isfinite(ref.est_max)) and ref.error_max >= 0.4  # not better than the MLP truly is


def test_an_outside_candidate_with_unpaired_residuals_is_refused():
    from nnik.machine.reference import fit_reference

    rng = np.random.default_rng(7)
    p = rng.uniform(0, 100, (60, 2))
    q = np.rint(p * [3.0, -2.0])
    with pytest.raises(ValueError, match="30 residuals for 20 positions"):
        fit_reference(p, q, None, extra={"mlp": (lambda pm: pm, p[:20], np.zeros((30, 2)))}, gp=False)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), g=st.integers(3, 60), d_scale=st.sampled_from([0.0, 0.01, 0.1, 1.0]),
       points=st.integers(1, 5000))
def test_the_claim_is_the_brute_force_on_random_fields(seed, g, d_scale, points):
    """The claim evaluates a few cells first and then only those that could beat them: the same
    figure as every point evaluated, whatever the grid, the points and d's size against the fields'."""
    rng = np.random.default_rng(seed)
    f = rng.normal(0, 0.1, (8, g, g, 2)).astype(np.float32)
    ef = ref_claim.ErrorFields(np.zeros(2), np.full(2, 10.0), f, np.ones((g, g), bool), "test")
    p = rng.uniform(0, 10, (points, 2))
    d = d_scale * np.sin(p[:, :1] * rng.uniform(0.1, 5) + np.array([0.0, 1.0])) + rng.normal(0, 0.01, (points, 2))
    cells = ef._cells(p)
    brute = [float(np.abs(d + ef.at(b, p, cells)).max()) for b in range(8)]
    assert ef.claim(p, d) == float(np.quantile(brute, ref_claim.LEVEL))
