"""Tuning against the identified model (here the scenario plant's linear model, standing for the
identified one): deterministic (same seed -> same gains), better than an untuned default, within
the overshoot limit, and the cross-coupled controller's contour error against the PID's."""

from __future__ import annotations

import pytest

from nnik.errors import NnikError
from nnik.implementations.servo import BASELINES
from nnik.implementations.servo.tune import evaluate, tune
from tests.implementations.servo.paths import circle, corner, plant_models, xy_table_cfg

TRIALS = 40
LIMIT_UM = 25.0
# The Arduino PID library's own example gains (PID_Basic.ino: Kp 2, Ki 5, Kd 1) on both axes
ARDUINO_EXAMPLE = dict(kp_x=2.0, ki_x=5.0, kd_x=1.0, kp_y=2.0, ki_y=5.0, kd_y=1.0)


@pytest.fixture(scope="module")
def setup():
    cfg = xy_table_cfg()
    return cfg, plant_models(cfg), {"corner": corner(cfg), "circle": circle(cfg)}


@pytest.fixture(scope="module")
def tuned(setup):
    cfg, models, paths = setup
    return {(k, p): tune(k, cfg, models, ref, TRIALS, 7, max_overshoot_um=LIMIT_UM)
            for k in BASELINES for p, ref in paths.items()}


def test_tuning_is_deterministic(setup, tuned):
    cfg, models, paths = setup
    assert tune("ccc", cfg, models, paths["corner"], TRIALS, 7, max_overshoot_um=LIMIT_UM) == tuned["ccc", "corner"]
    assert tune("pid", cfg, models, paths["corner"], TRIALS, 8, max_overshoot_um=LIMIT_UM) != tuned["pid", "corner"]


@pytest.mark.parametrize("path", ["corner", "circle"])
def test_tuned_pid_beats_the_arduino_example_gains(setup, tuned, path):
    cfg, models, paths = setup
    untuned = evaluate("pid", ARDUINO_EXAMPLE, cfg, models, paths[path], LIMIT_UM)
    best = evaluate("pid", tuned["pid", path], cfg, models, paths[path], LIMIT_UM)
    assert best["objective"] < untuned["objective"]
    assert best["rms_contour_um"] < untuned["rms_contour_um"]


@pytest.mark.parametrize("kind", BASELINES)
@pytest.mark.parametrize("path", ["corner", "circle"])
def test_each_tuned_controller_meets_its_limits_on_the_model(setup, tuned, kind, path):
    cfg, models, paths = setup
    s = evaluate(kind, tuned[kind, path], cfg, models, paths[path], LIMIT_UM)
    assert s["within_limits"], s
    assert s["overshoot_um"] <= LIMIT_UM and s["final_error_um"] <= LIMIT_UM and s["saturated_fraction"] <= 0.05


def test_ccc_holds_the_circle_at_least_as_well_as_the_pid(setup, tuned):
    """On the corner the tuned CCC is not always ahead (docs/closed_loop.md gives the figures)."""
    cfg, models, paths = setup
    pid = evaluate("pid", tuned["pid", "circle"], cfg, models, paths["circle"], LIMIT_UM)
    ccc = evaluate("ccc", tuned["ccc", "circle"], cfg, models, paths["circle"], LIMIT_UM)
    assert ccc["rms_contour_um"] <= pid["rms_contour_um"], (ccc, pid)


def test_bad_tuning_requests_are_one_error(setup):
    cfg, models, paths = setup
    with pytest.raises(NnikError, match="at least 2 ticks"):
        tune("pid", cfg, models, paths["corner"][:1], 5, 1)
    with pytest.raises(NnikError, match="tune_trials"):
        tune("pid", cfg, models, paths["corner"], 0, 1)
    with pytest.raises(NnikError, match="unknown controller kind"):
        tune("lqr", cfg, models, paths["corner"], 3, 1)


def test_the_tuning_model_sticks_below_its_coulomb_friction(setup):
    """With the identified Coulomb friction (volts), a duty below it leaves the axis at rest and a
    moving axis that friction stops does not reverse; without it the same duty moves the axis."""
    from nnik.implementations.servo.model_loop import simulate_model

    cfg, models, _ = setup

    class Hold:
        def __init__(self, duty):
            self.duty = duty

        def reset(self):
            pass

        def tick(self, ref, pos):
            return self.duty

    ref = [[0, 0]] * 50
    weak = round(0.9 * cfg.duty_max / cfg.supply_v)  # 0.9 V
    pos, _ = simulate_model(cfg, models, Hold((weak, -weak)), ref, coulomb_v=(1.0, 1.0))
    assert (pos == 0.5).all()
    pos, _ = simulate_model(cfg, models, Hold((weak, -weak)), ref)
    assert pos[-1, 0] > 100 and pos[-1, 1] < -100

    class Coast(Hold):
        def tick(self, ref, pos):
            self.k = getattr(self, "k", -1) + 1
            return (cfg.duty_max, 0) if self.k < 20 else (0, 0)

    pos, _ = simulate_model(cfg, models, Coast(None), ref, coulomb_v=(2.0, 0.0))
    assert (pd := pos[:, 0])[-1] > pd[20] and (pd[1:] >= pd[:-1]).all()  # stops, never runs back
    assert pd[-1] == pd[-5]
