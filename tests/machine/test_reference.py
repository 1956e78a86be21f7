"""Measured machines: the reference model fitted to the marks and the honesty of the accuracy
claimed for the pick, on random machines with a known truth (seeded, deterministic).

Random belt frames (CoreXY/HBOT, skew and distortion) are 'measured' with nnik.machine.synth: marks
scattered or on a grid, whole-microstep counter readings (+-0.5 of rounding). The reference and
the families' ladders (poly, lut, hybrid; no MLP training, no simulators) then run as in
`nnik run`, on a coarser check grid. The claimed max error of every family's best that meets
max_error (the bootstrap of nnik.machine.ref_claim) must not be better than the truth by more
than HONEST, nor worse than claim_over(n) times it (HONEST x true <= claimed <= claim_over(n) x true,
true: the max over the marks' hull). Hypothesis draws the frames (NNIK_HYPOTHESIS_MACHINES, 3 in
CI); `make bench` runs more, and the larger sweep (python -m nnik.bench.measured --sweep N).
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik import pipeline

from nnik.machine import reference
from nnik.bench.measured import HONEST, claim_over, measured_toml, random_belt_toml
from nnik.machine.data import build_dataset, exact_targets
from nnik.errors import NnikError
from nnik.implementations import problem as problem_mod
from nnik.machine.scenario import load_scenario
from nnik.machine.synth import synthesize_measurements

FAMILIES = ["poly", "lut", "hybrid"]
EXAMPLES = int(os.environ.get("NNIK_HYPOTHESIS_MACHINES", "3"))


def measured_machine(tmp_path, seed: int, n: int, sampling: str, inset_mm: float = 5.0):
    """(truth scenario, measured scenario) for a random belt frame measured at n marks."""
    rng = np.random.default_rng(seed)
    (tmp_path / "truth.toml").write_text(random_belt_toml(rng, f"truth{seed}"))
    truth = load_scenario(tmp_path / "truth.toml")
    csv = tmp_path / "marks.csv"
    synthesize_measurements(truth, csv, n, 0.0, seed, readings="rounded", sampling=sampling, inset_mm=inset_mm)
    (tmp_path / "marks.toml").write_text(measured_toml(f"marks{seed}", csv, truth))
    return truth, load_scenario(tmp_path / "marks.toml")


@pytest.fixture
def coarse_check(monkeypatch):
    """A 201 x 201 check grid and 5,000 random points: the property, not the last digit."""
    grid = problem_mod.dense_grid
    monkeypatch.setattr(problem_mod, "dense_grid", lambda lo, hi: grid(lo, hi, 201, 401))
    monkeypatch.setattr(problem_mod, "CHECK_RANDOM", 5000)


def test_synth_rounded_readings_are_the_exact_ik_rounded(tmp_path):
    truth, scn = measured_machine(tmp_path, 3, 49, "grid")
    p, q = scn.mechanism.positions_mm, scn.mechanism.commands
    assert len(p) == 49 and np.all(q == np.rint(q))
    assert np.abs(q - exact_targets(truth, p)).max() <= 0.51  # and the CSV's 0.1 um of precision
    assert np.abs(q - exact_targets(truth, p)).max() > 0.3  # they are rounded, not exact


def test_stated_rounding_is_the_noise_model(tmp_path):
    _, scn = measured_machine(tmp_path, 4, 60, "sobol")
    noise = reference.scenario_noise(scn)
    assert noise.variance == pytest.approx([1 / 12, 1 / 12]) and noise.bound == pytest.approx([0.5, 0.5])
    assert "rounded" in noise.source


@settings(max_examples=EXAMPLES, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), n=st.sampled_from([49, 100, 150, 200, 400]),
       sampling=st.sampled_from(["sobol", "grid"]))
def test_claimed_accuracy_is_within_its_margin_of_the_truth(tmp_path_factory, coarse_check, seed, n, sampling):
    from nnik import selection as sel

    truth, scn = measured_machine(tmp_path_factory.mktemp("frame"), seed, n, sampling)
    problem = pipeline.build_problem(scn, build_dataset(scn))
    ref = problem.reference
    assert ref.name in ref.scores and "cv_rms" in ref.scores[ref.name]
    cv = {k: float(np.mean(np.square(v["cv_rms"]))) for k, v in ref.scores.items() if "cv_rms" in v}
    assert ref.name == min(cv, key=cv.get)  # the lowest CV error is the one chosen
    pts, ref_q = problem.check
    assert len(pts) > 1000 and ref.hull.inside(problem.to_mm(pts), 1e-6).all()
    exact = exact_targets(truth, problem.to_mm(pts))
    ref_true = np.abs(ref_q - exact).max()
    assert HONEST * ref_true <= ref.error_max <= claim_over(n) * ref_true, (ref.error_max, ref_true)
    # no [target]: the default is defined and above the reference's own error
    assert problem.scn.target["max_error"] >= max(0.25, ref.error_max)
    assert problem.scn.target["max_error_source"].startswith("default")
    cands = sel.fit_ladder(problem, FAMILIES, max_error=problem.scn.target["max_error"])
    bests = [c for c in sel.family_bests(cands, problem.scn.target).values() if c.meets(problem.scn.target["max_error"])]
    assert bests, "no family meets the default max_error"
    for c in bests:
        true = np.abs(c.impl.run(pts).pre - exact).max()
        # the claim combines the implementation's error field with the reference's: never more
        # than their maxima added
        assert c.claimed_max <= c.acc["pre_max"] + ref.fields.emax + 1e-9
        assert HONEST * true <= c.claimed_max <= claim_over(n) * true, (c.impl.describe(), c.claimed_max, true)


def test_header_names_the_reference_not_the_exact_ik(tmp_path, coarse_check):
    from nnik.implementations import FAMILIES as FAMS

    _, scn = measured_machine(tmp_path, 5, 49, "grid")
    problem = pipeline.build_problem(scn, build_dataset(scn))
    impl = FAMS["poly"].fit(problem, FAMS["poly"].ladder(problem)[0])
    header = next(v for k, v in impl.render_c().items() if k.endswith(".h"))
    assert "exact IK" not in header
    assert f"the reference model ({problem.reference.name}) fitted to 49 marks" in header


def test_workspace_beyond_the_marks_warns(tmp_path):
    _, scn = measured_machine(tmp_path, 6, 49, "grid", inset_mm=10.0)
    ref = reference.reference_for(scn)
    assert "extends beyond the marks" in ref.extra["workspace_warning"]
    assert ref.to_dict()["workspace_warning"] == ref.extra["workspace_warning"]
    covered = reference.hull_warning(reference.convex_hull(np.array([[0, 0], [0, 150], [150, 0], [150, 150.0]])),
                                     scn.workspace)
    assert covered is None or scn.workspace.hi[0] > 150


def test_given_max_error_is_kept_and_the_default_follows_the_floor(tmp_path):
    _, scn = measured_machine(tmp_path, 7, 49, "grid")
    assert pipeline.with_default_target(scn, 0.0).target["max_error"] == 0.25
    assert pipeline.with_default_target(scn, 0.8).target["max_error"] == pytest.approx(1.0)
    raw = {**scn.raw, "target": {"max_error": 2.0}}
    given = type(scn).from_dict(raw, scn.source, scn.base_dir)
    assert pipeline.with_default_target(given, 0.8).target["max_error"] == 2.0


@pytest.mark.parametrize("key,value", [("reading_step", -1.0), ("noise_um", float("nan")), ("noise_um", 1e9)])
def test_bad_noise_values_are_refused(tmp_path, key, value):
    _, scn = measured_machine(tmp_path, 8, 49, "grid")
    raw = {**scn.raw, "mechanism": {**scn.raw["mechanism"], key: value}}
    with pytest.raises(NnikError, match=key):
        type(scn).from_dict(raw, scn.source, scn.base_dir)
