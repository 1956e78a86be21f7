"""contour.path_dist_um (moves grouped, small groups stacked) against its definition: for each
move's points, the least move_dist to that move and its neighbours, one boolean mask per move.
Equal to the last bit: the job's contour figures must not move."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.firmware.gcode.contour import move_dist, path_dist_um
from nnik.firmware.gcode.motion import Move


def by_mask(p_mm, move_idx, moves, origin_mm):
    d = np.full(len(p_mm), np.inf)
    for m in np.unique(move_idx):
        sel = move_idx == m
        for k in (m - 1, m, m + 1):
            if 0 <= k < len(moves):
                d[sel] = np.minimum(d[sel], move_dist(p_mm[sel], moves[k], origin_mm))
    return d * 1000.0


def random_moves(rng, n):
    moves, pos = [], (0, 0)
    for i in range(n):
        end = tuple(int(v) for v in rng.integers(-40000, 40000, 2)) if rng.random() > 0.1 else pos  # some zero-length
        if rng.random() < 0.3:
            c = tuple(int(v) for v in rng.integers(-40000, 40000, 2))
            r = int(np.hypot(pos[0] - c[0], pos[1] - c[1]))
            moves.append(Move(i, "arc", pos, end, i, 1, c, r, bool(rng.random() < 0.5)))
        else:
            moves.append(Move(i, "line", pos, end, i, 1))
        pos = end
    return moves


@settings(max_examples=25, deadline=None, database=None)
@given(seed=st.integers(0, 2**31), n_moves=st.integers(1, 60), big=st.booleans())
def test_grouped_distances_are_the_masked_ones(seed, n_moves, big):
    rng = np.random.default_rng(seed)
    moves = random_moves(rng, n_moves)
    sizes = rng.integers(1, 400 if big else 12, n_moves)
    move_idx = np.repeat(np.arange(n_moves), sizes)
    rng.shuffle(move_idx[: len(move_idx) // 3])  # not always in order
    p = rng.normal(size=(len(move_idx), 2)) * 30.0
    origin = np.array([1.5, -2.25])
    assert np.array_equal(path_dist_um(p, move_idx, moves, origin), by_mask(p, move_idx, moves, origin))
