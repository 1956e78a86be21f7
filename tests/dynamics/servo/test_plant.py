"""The plant against its physics: steady states, the exact discretisation, friction, backlash,
signs and energy, on random plants (hypothesis)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from hypothesis import given, settings, strategies as st
from scipy.integrate import solve_ivp

from nnik.dynamics.servo.motor import continuous
from nnik.dynamics.servo.plant import Plant
from tests.dynamics.servo.plants import configs

FAST = settings(max_examples=20, deadline=None)


def run(plant: Plant, duty, ticks: int) -> list[np.ndarray]:
    """Step `ticks` ticks with duty held; every tick's per-axis substep states, stacked per axis."""
    states = [[], []]
    for _ in range(ticks):
        plant.step(duty)
        for a in range(2):
            states[a].append(plant.last_states[a])
    return [np.concatenate(s) for s in states]


@FAST
@given(cfg=configs(stiction=True), sign=st.sampled_from([1, -1]))
def test_full_duty_runs_at_the_steady_state_of_ke_ra_and_friction(cfg, sign):
    plant = Plant(cfg)
    ticks = math.ceil(15 * max(ax.tau_m_s for ax in cfg.axes) / cfg.tick_s)
    run(plant, (sign * cfg.duty_max, sign * cfg.duty_max), ticks)
    for a, ax in enumerate(cfg.axes):
        i, w, _ = plant.state(a)
        want = ax.free_speed_rad_s(cfg.supply_v)
        assert math.isclose(w, sign * want, rel_tol=1e-4), (w, want)
        assert math.isclose(i, sign * ax.no_load_current_a(cfg.supply_v), rel_tol=1e-3,
                            abs_tol=1e-6 * ax.stall_current_a(cfg.supply_v))


@FAST
@given(cfg=configs(stiction=True), frac=st.floats(0.05, 0.95))
def test_held_below_break_away_the_rotor_is_blocked_and_draws_v_over_ra(cfg, frac):
    # a duty whose stall torque stays below the break-away torque: the axis never moves, and the
    # current settles at the stall current of that voltage
    ax = cfg.axes[0]
    volts = frac * ax.break_away_n_m * ax.ra_ohm / ax.ke_v_s_rad
    duty = math.floor(volts / cfg.supply_v * cfg.duty_max)
    plant = Plant(cfg, (100, -7))
    states = run(plant, (duty, 0), 40)[0]
    assert np.all(states[:, 1] == 0.0) and np.all(states[:, 2] == states[0, 2])  # still, no chatter
    assert plant.counts == (100, -7)
    assert math.isclose(states[-1, 0], cfg.volts(duty) / ax.ra_ohm, rel_tol=1e-9, abs_tol=1e-12)


@FAST
@given(cfg=configs(stiction=True), sign=st.sampled_from([1, -1]))
def test_above_break_away_it_moves_in_the_torques_direction(cfg, sign):
    ax = cfg.axes[1]
    volts = 1.1 * ax.break_away_n_m * ax.ra_ohm / ax.ke_v_s_rad
    duty = sign * min(cfg.duty_max, math.ceil(volts / cfg.supply_v * cfg.duty_max))
    plant = Plant(cfg)
    states = run(plant, (0, duty), 60)[1]
    assert np.all(np.sign(states[:, 1]) != -sign)
    assert (states[-1, 2] - states[0, 2]) * sign > 0
    assert plant.counts[1] * sign > 0 and plant.counts[0] == 0


@settings(max_examples=10, deadline=None)
@given(cfg=configs(coulomb=False), seed=st.integers(0, 2**31))
def test_the_exact_discretisation_matches_solve_ivp(cfg, seed):
    duties = np.random.default_rng(seed).integers(-cfg.duty_max, cfg.duty_max + 1, size=(6, 2))
    plant = Plant(cfg)
    x0 = [np.array(plant.state(a)) for a in range(2)]
    got = [[], []]
    for d in duties:
        plant.step(tuple(d))
        for a in range(2):
            got[a].append(plant.last_states[a][-1])
    for a, ax in enumerate(cfg.axes):
        am, bm = continuous(ax)
        x = x0[a]
        for k, d in enumerate(duties[:, a]):
            u = np.array([cfg.volts(int(d)), 0.0])
            sol = solve_ivp(lambda t, y: am @ y + bm @ u, (0, cfg.tick_s), x, method="Radau",
                            jac=am, rtol=1e-11, atol=1e-12)
            x = sol.y[:, -1]
            for j, atol in enumerate((1e-6, 1e-6, 1e-9)):  # A, rad/s, rad
                assert math.isclose(got[a][k][j], x[j], rel_tol=1e-6, abs_tol=atol), (k, j, got[a][k], x)


@FAST
@given(cfg=configs(stiction=True, backlash=True))
def test_backlash_the_table_waits_until_the_play_is_taken(cfg):
    plant = Plant(cfg, (0, 0))
    run(plant, (cfg.duty_max, cfg.duty_max), 30)  # forward: the table trails by half the play
    for _ in range(10_000):  # until both axes rest
        run(plant, (0, 0), 1)
        if all(np.all(plant.last_states[a][:, 1] == 0.0) for a in range(2)):
            break
    t0 = np.array(plant.table_um)
    for a, ax in enumerate(cfg.axes):
        motor_um = plant.state(a)[2] * cfg.lead_mm * 1000 / (2 * math.pi * ax.gear_ratio)
        assert math.isclose(motor_um - t0[a], ax.backlash_um / 2, rel_tol=1e-9, abs_tol=1e-9)
    start = [plant.state(a)[2] for a in range(2)]
    c0 = plant.counts
    table, motor = [], [[], []]
    for _ in range(60):  # reverse
        plant.step((-cfg.duty_max, -cfg.duty_max))
        table.append(plant.last_table_um)
        for a in range(2):
            motor[a].append(plant.last_states[a][:, 2])
    table = np.concatenate(table)
    for a, ax in enumerate(cfg.axes):
        back_um = (start[a] - np.concatenate(motor[a])) * cfg.lead_mm * 1000 / (2 * math.pi * ax.gear_ratio)
        inside = back_um <= ax.backlash_um
        assert inside[0] and not inside[-1]
        assert np.all(table[inside, a] == t0[a])  # the table stands while the gear crosses the gap
        np.testing.assert_allclose(table[~inside, a], t0[a] + ax.backlash_um - back_um[~inside], atol=1e-6)
        assert plant.counts[a] < c0[a]  # the motor's encoder saw the whole way back


@FAST
@given(cfg=configs(stiction=True), duty=st.integers(1, 255))
def test_signs_mirror(cfg, duty):
    fwd, rev = Plant(cfg), Plant(cfg)
    sf, sr = run(fwd, (duty, duty), 20), run(rev, (-duty, -duty), 20)
    for a in range(2):
        assert np.all(sf[a][:, 0] >= 0) or duty < cfg.duty_max  # current follows the duty at free run
        np.testing.assert_allclose(sf[a][:, :2], -sr[a][:, :2], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sf[a][:, 2] - sf[a][0, 2], -(sr[a][:, 2] - sr[a][0, 2]), atol=1e-9)
        assert fwd.counts[a] >= 0 >= rev.counts[a]
        assert (fwd.table_um[a] >= rev.table_um[a])


@FAST
@given(cfg=configs(), duty=st.integers(-255, 255))
def test_energy_in_is_stored_plus_dissipated(cfg, duty):
    cfg = replace(cfg, substeps=cfg.substeps * 8)
    plant = Plant(cfg)
    s = run(plant, (duty, duty), 30)
    h = cfg.tick_s / cfg.substeps
    for a, ax in enumerate(cfg.axes):
        i = np.concatenate([[0.0], s[a][:, 0]])
        w = np.concatenate([[0.0], s[a][:, 1]])
        volts = cfg.volts(duty)
        supplied = np.trapezoid(volts * i, dx=h)
        lost = np.trapezoid(ax.ra_ohm * i * i + ax.viscous_n_m_s_rad * w * w + ax.coulomb_n_m * np.abs(w), dx=h)
        stored = 0.5 * ax.j_kg_m2 * w[-1] ** 2 + 0.5 * ax.la_h * i[-1] ** 2
        assert supplied >= -1e-12
        assert math.isclose(supplied, lost + stored, rel_tol=2e-3, abs_tol=1e-9)


@settings(max_examples=10, deadline=None)
@given(cfg=configs(stiction=True), over=st.integers(1, 10_000), frac=st.floats(-0.49, 0.49))
def test_the_duty_is_an_integer_saturated_at_duty_max(cfg, over, frac):
    a, b = Plant(cfg), Plant(cfg)
    dm = cfg.duty_max
    for _ in range(5):
        np.testing.assert_array_equal(a.step((dm + over, -dm - over)), b.step((dm, -dm)))
        np.testing.assert_array_equal(a.step((100 + frac, -37 + frac)), b.step((100, -37)))
    assert a.state(0) == b.state(0) and a.state(1) == b.state(1)
