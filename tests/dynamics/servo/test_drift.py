"""The drifting and the differing plants (nnik.dynamics.servo.drift): no drift is Plant exactly;
the drift's last piece is the drifted parameters' plant (its free speed, lower); the differing
plant is the stated factors."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from nnik.dynamics.servo.drift import DIFFERING, JOB_DRIFT, NOMINAL, Drift, DriftPlant, differing
from nnik.dynamics.servo.plant import Plant
from tests.dynamics.servo.plants import configs

FAST = settings(max_examples=15, deadline=None)


@FAST
@given(cfg=configs(stiction=True, backlash=True), seed=st.integers(0, 2**16), pieces=st.integers(2, 7))
def test_no_drift_is_the_plant_exactly(cfg, seed, pieces):
    rng = np.random.default_rng(seed)
    duties = rng.integers(-cfg.duty_max, cfg.duty_max + 1, size=(30, 2))
    a, b = Plant(cfg, (5, -3)), DriftPlant(cfg, 30, NOMINAL, pieces, (5, -3))
    for d in duties.tolist():
        assert np.array_equal(a.step(d), b.step(d))
        assert a.table_um == b.table_um and a.counts == b.counts


@FAST
@given(cfg=configs(stiction=True), sign=st.sampled_from([1, -1]))
def test_the_last_piece_runs_at_the_drifted_free_speed(cfg, sign):
    drifted = JOB_DRIFT.apply(cfg)
    settle = math.ceil(15 * max(ax.tau_m_s for ax in drifted.axes) / cfg.tick_s)
    ticks = 4 * settle  # 4 pieces: the last one long enough to settle
    plant = DriftPlant(cfg, ticks, JOB_DRIFT, 4)
    for _ in range(ticks):
        plant.step((sign * cfg.duty_max, sign * cfg.duty_max))
    assert plant.cfg == drifted
    for a in range(2):
        w = plant.state(a)[1]
        want = drifted.axes[a].free_speed_rad_s(drifted.supply_v)
        assert math.isclose(w, sign * want, rel_tol=1e-4), (w, want)
        assert abs(w) < cfg.axes[a].free_speed_rad_s(cfg.supply_v)  # slower than the nominal


@FAST
@given(cfg=configs(), ticks=st.integers(2, 500), pieces=st.integers(2, 12))
def test_the_ramp_starts_nominal_ends_drifted_and_never_goes_back(cfg, ticks, pieces):
    plant = DriftPlant(cfg, ticks, JOB_DRIFT, min(pieces, ticks))
    fr = [plant.fraction(k) for k in range(ticks + 5)]
    assert fr[0] == 0.0 and fr[ticks - 1] == 1.0 and fr[-1] == 1.0
    assert all(b >= a for a, b in zip(fr, fr[1:]))


def test_the_stated_factors():
    assert JOB_DRIFT == Drift(inertia=1.5, friction=2.0, supply=0.8)
    assert DIFFERING == Drift(inertia=1.4, friction=1.5, ke=0.9, ra=1.2)


@FAST
@given(cfg=configs(stiction=True))
def test_the_differing_plant_is_slower_and_weaker(cfg):
    d = differing(cfg)
    for a, (n, o) in enumerate(zip(cfg.axes, d.axes)):
        assert o.j_kg_m2 == n.j_kg_m2 * 1.4 and o.ra_ohm == n.ra_ohm * 1.2 and o.ke_v_s_rad == n.ke_v_s_rad * 0.9
        assert o.coulomb_n_m == n.coulomb_n_m * 1.5 and o.stiction_n_m == n.stiction_n_m * 1.5
        assert o.stall_current_a(12.0) * o.ke_v_s_rad < n.stall_current_a(12.0) * n.ke_v_s_rad


@FAST
@given(cfg=configs(stiction=True, backlash=True), seed=st.integers(0, 2**16), pieces=st.integers(2, 5))
def test_each_piece_is_the_plant_of_its_parameters_exactly(cfg, seed, pieces):
    """From a piece's first tick the drifting plant steps exactly as a Plant built with that piece's
    parameters and handed the same state (current, speed, angle, stuck, counts, table)."""
    rng = np.random.default_rng(seed)
    per = 6
    plant = DriftPlant(cfg, per * pieces, JOB_DRIFT, pieces, (7, 9))
    duties = rng.integers(-cfg.duty_max, cfg.duty_max + 1, size=(per * pieces, 2)).tolist()
    for p in range(pieces):
        twin = Plant(JOB_DRIFT.at(p / (pieces - 1)).apply(cfg))
        twin._x, twin._stuck = [x.copy() for x in plant._x], list(plant._stuck)
        twin._counts, twin._table = list(plant._counts), list(plant._table)
        for d in duties[p * per:(p + 1) * per]:
            assert np.array_equal(plant.step(d), twin.step(d))
            assert plant.table_um == twin.table_um
        assert plant.cfg == twin.cfg
