"""The encoder: quadrature counts from the motor angle, and the seed's 8-bit counters, which wrap
and are unwrapped each reading."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import assume, given, settings, strategies as st

from nnik.dynamics.servo import encoder
from nnik.dynamics.servo.plant import Plant
from nnik.machine.servo import servo_problems
from tests.dynamics.servo.plants import configs


@given(start=st.integers(-2**31, 2**31 - 1), steps=st.lists(st.integers(-127, 127), min_size=1, max_size=200))
def test_counter8_unwraps_every_move_under_half_a_turn(start, steps):
    true = start + np.cumsum(steps)
    prev, got = start, []
    for c in true:
        prev = int(encoder.unwrap8(prev, encoder.raw8(int(c))))
        got.append(prev)
    assert got == true.tolist()


@given(start=st.integers(-10**6, 10**6), step=st.integers(129, 10_000).filter(lambda s: s % 256))
def test_counter8_aliases_a_move_past_half_a_turn(start, step):
    got = int(encoder.unwrap8(start, encoder.raw8(start + step)))
    assert got != start + step and (got - (start + step)) % 256 == 0


def test_quadrature_counts_are_the_floor_of_the_angle():
    per_rev = 64.0
    angles = np.array([-1e-12, 0.0, 2 * np.pi / 64 * 0.999, 2 * np.pi / 64 * 1.001, -2 * np.pi])
    assert encoder.counts(angles, per_rev).tolist() == [-1, 0, 0, 1, -64]


@settings(max_examples=10, deadline=None)
@given(cfg=configs(stiction=True), seed=st.integers(0, 2**31))
def test_counter8_plant_reads_the_quadrature_plants_counts_through_its_wrapping_8_bits(cfg, seed):
    duties = np.random.default_rng(seed).integers(-cfg.duty_max, cfg.duty_max + 1, size=(40, 2))
    duties = np.repeat(duties, 5, axis=0)  # held 5 ticks each: the counters go round
    c8 = replace(cfg, encoder="counter8", tick_s=0.001, substeps=max(4, cfg.substeps // 5))
    assume(servo_problems(c8) == [])  # the check refuses a counter that wraps past half a turn a tick
    quad, eight = Plant(replace(c8, encoder="quadrature"), (250, -3)), Plant(c8, (250, -3))
    raws = set()
    for d in duties:
        rq, r8 = quad.step(tuple(d)), eight.step(tuple(d))
        np.testing.assert_array_equal(rq, r8)
        assert eight.raw8 == (eight.counts[0] & 0xFF, eight.counts[1] & 0xFF)
        raws.add(eight.raw8[0])
    assert max(abs(c) for c in eight.counts) > 300 or len(raws) > 1  # it moved; unwrapping mattered
