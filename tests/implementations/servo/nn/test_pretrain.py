"""Pretraining (nnik.implementations.servo.nn.pretrain): deterministic, the log's verification is
what the returned weights do from power-on, the stop rule is the stated 2 %, and bad requests are
one error line."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from nnik.dynamics.servo.speed_model import SpeedModel
from nnik.errors import NnikError
from nnik.implementations.servo.nn.params import check_params
from nnik.implementations.servo.nn.pretrain import TOLERANCE, pretrain, run_test, seed_steps
from tests.implementations.servo.paths import xy_table_cfg

CFG = xy_table_cfg()
MODELS = (SpeedModel(868.0, 0.0295), SpeedModel(843.0, 0.0446))
COULOMB = (0.19, 0.27)


@pytest.mark.parametrize("kind", ["nn_axes", "nn_vector"])
def test_same_seed_same_params_and_the_log_is_what_they_do(kind):
    a, log_a = pretrain(kind, CFG, MODELS, COULOMB, seed=3, episodes=2)
    b, log_b = pretrain(kind, CFG, MODELS, COULOMB, seed=3, episodes=2)
    assert a == b and log_a == log_b
    assert check_params(kind, a) == a
    assert a["eta_shift"] == log_a["eta_shift"] and a["in_shift"] == log_a["in_shift"]
    for name, ref in seed_steps(CFG):  # the verification: the returned weights from power-on
        _, fig = run_test(kind, a, CFG, MODELS, COULOMB, ref)
        assert fig == log_a["verify"][name]
    c, _ = pretrain(kind, CFG, MODELS, COULOMB, seed=4, episodes=2)
    assert c["w1"] != a["w1"]


@settings(max_examples=4, deadline=None)
@given(k=st.floats(300.0, 2000.0), tau=st.floats(0.015, 0.08), seed=st.integers(0, 1000))
def test_the_stop_rule_is_two_percent_of_the_reference(k, tau, seed):
    models = (SpeedModel(k, tau), SpeedModel(k * 0.9, tau * 1.3))
    _, log = pretrain("nn_vector", CFG, models, (0.0, 0.0), seed=seed, episodes=2)
    for g in log["grid"]:
        # an episode passes exactly when every test's steady-state error and overshoot are under 2 %
        worst = max(max(f["steady_state_um"], f["overshoot_um"]) / f["allowed_um"] for f in g["last_episode"].values())
        assert g["passed"] == (worst < 1.0) and g["episode_worst"][-1] == pytest.approx(worst)
        assert all(f["allowed_um"] == pytest.approx(TOLERANCE * (25_000 if "x" in n else 20_000), rel=1e-3)
                   for n, f in g["last_episode"].items())
        assert g["passed"] or g["episodes"] == 2  # stops at the first pass, else at the budget
    assert log["passed"] == any(g["passed"] for g in log["grid"])


@pytest.mark.parametrize("kind, episodes", [("pid", 2), ("nn_axes", 0), ("nn_axes", 1.5), ("nn_axes", True)])
def test_bad_requests_are_one_error(kind, episodes):
    with pytest.raises(NnikError):
        pretrain(kind, CFG, MODELS, COULOMB, seed=1, episodes=episodes)
