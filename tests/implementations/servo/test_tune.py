"""Tuning against the identified model (here the scenario plant's linear model, standing for the
identified one): deterministic (same seed -> same gains), better than an untuned default, within
the overshoot limit, and the cross-coupled controller's contour error against the PID's."""

from __future__ import annotations

import pytest

from nnik.errors import NnikError
from nnik.implementations.servo import KINDS
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
            for k in KINDS for p, ref in paths.items()}


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


@pytest.mark.parametrize("kind", KINDS)
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
