"""The default controller of `nnik run` on a dc_servo xy_table (issue 29 item 6): scored on the
IDENTIFIED plant (the speed models, not the scenario's plant), the lowest RMS contour error wins, a
diverged neural run never does, ties go to the earlier kind, and [controller] kind overrides with
the reason named."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.commands.servo_default import choose, identified_scores
from nnik.dynamics.servo.speed_model import SpeedModel
from nnik.implementations.servo import KINDS, make
from nnik.job.parse import JobRequest
from nnik.job.reference import job_reference
from nnik.machine.scenario import load_scenario
from tests.implementations.servo.nn_params import seeded_nn_params

REF_JOB = "datasets/jobs/xy_table_reference.gcode"


@pytest.fixture(scope="module")
def setup():
    scn = load_scenario("datasets/xy_table.toml")
    _, ref = job_reference(JobRequest(__import__("pathlib").Path(REF_JOB), scn))
    return scn, ref


def test_scores_are_the_identified_plants(setup):
    """The same controller on two identified models scores differently (the model is what is
    scored); a PID that cannot move scores worse than one that follows."""
    scn, ref = setup
    cfg = scn.servo
    pid = dict(kp_x=2.0, ki_x=0.0, kd_x=0.02, kp_y=2.0, ki_y=0.0, kd_y=0.02)
    still = {k: 0.0 for k in pid}
    fast = (SpeedModel(900.0, 0.03), SpeedModel(850.0, 0.045))
    slow = (SpeedModel(300.0, 0.12), SpeedModel(280.0, 0.15))
    a = identified_scores(cfg, fast, (0.0, 0.0), {"pid": make("pid", pid, cfg)}, ref)["pid"]
    b = identified_scores(cfg, slow, (0.0, 0.0), {"pid": make("pid", pid, cfg)}, ref)["pid"]
    c = identified_scores(cfg, fast, (0.0, 0.0), {"pid": make("pid", still, cfg)}, ref)["pid"]
    assert a["rms_um"] != b["rms_um"] and c["rms_um"] > a["rms_um"] > 0
    assert a["max_um"] >= a["rms_um"] and not a["diverged"]
    assert c["path_rms_um"] == 0.0  # a still carriage sits on the path's start: the whole path's distance is blind


def test_a_diverging_neural_run_is_flagged(setup):
    """Weights at their clamps with the fastest learning rate: clamps pass 1 % of the updates."""
    scn, ref = setup
    cfg = scn.servo
    p = seeded_nn_params("nn_axes", 2, cfg, eta_shift=0)
    s = identified_scores(cfg, (SpeedModel(900.0, 0.03), SpeedModel(850.0, 0.045)), (0.0, 0.0),
                          {"nn_axes": make("nn_axes", p, cfg)}, ref)["nn_axes"]
    assert s["diverged"]


SCORES = st.dictionaries(st.sampled_from(KINDS), st.tuples(st.floats(0, 500), st.booleans()), min_size=1).map(
    lambda d: {k: {"rms_um": r, "max_um": 2 * r, "diverged": dv} for k, (r, dv) in sorted(d.items(),
                                                                                        key=lambda i: KINDS.index(i[0]))})


@settings(max_examples=200)
@given(scores=SCORES)
def test_choose_picks_the_lowest_that_did_not_diverge(scores):
    best, why = choose("auto", scores, "ref.gcode")
    fit = [k for k, s in scores.items() if not s["diverged"]] or list(scores)
    low = min(scores[k]["rms_um"] for k in fit)
    assert best == next(k for k in fit if scores[k]["rms_um"] == low)  # ties: the earlier kind
    assert why.startswith("the lowest RMS contour error (tuning's: to the path within +-0.5 s) on ref.gcode on the "
                          "identified plant")
    assert all(k in why for k, s in scores.items() if s["diverged"] and fit != list(scores))


def test_the_scenarios_kind_overrides_and_says_so():
    scores = {"pid": {"rms_um": 9.0, "max_um": 20.0, "diverged": False},
              "nn_vector": {"rms_um": 4.0, "max_um": 9.0, "diverged": False}}
    best, why = choose("pid", scores, "ref.gcode")
    assert best == "pid" and "[controller] kind = 'pid'" in why and "is nn_vector's (4.0 um, pid 9.0 um)" in why
