"""Random controller inputs for the servo controllers' tests: gains drawn as their fixed-point
values (so any value of each format is reachable) and (ref, pos) sequences of holds, ramps,
reversals and jumps, with position errors from zero to far beyond saturation."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import strategies as st

from nnik.implementations.servo import NEURAL
from tests.implementations.servo.nn_params import nn_params, seeded_nn_params

TICK_S = 0.005
CFG = SimpleNamespace(tick_s=TICK_S, duty_max=255)
Q8, Q16 = 256.0, 65536.0


# a format's small values as often as its large ones (most of the range saturates the duty at once)
Q_VALUES = st.one_of(st.integers(0, 255), st.integers(0, 4095), st.integers(0, 65535))


def q8(draw) -> float:
    return draw(Q_VALUES) / Q8


@st.composite
def gains(draw, kind: str, tick_s: float = TICK_S) -> dict:
    if kind in NEURAL:
        return draw(nn_params(kind))
    g = {}
    pid_like = kind in ("pid", "ccc")
    for a in ("x", "y"):
        g[f"kp_{a}"] = q8(draw)
        g[f"kd_{a}"] = q8(draw) * tick_s
        if pid_like:
            g[f"ki_{a}"] = draw(Q_VALUES) / Q16 / tick_s
        else:
            win = 4
            g[f"kv_{a}"] = q8(draw) * win * tick_s
            g[f"ka_{a}"] = q8(draw) * (win * tick_s) ** 2
            g[f"kf_{a}"] = draw(st.integers(0, 255))
    if kind == "ccc":
        g["kcp"] = q8(draw)
        g["kcd"] = q8(draw) * tick_s
        g["min_chord"] = draw(st.integers(1, 20))
    if kind != "pid":
        g["win"] = draw(st.sampled_from([1, 2, 4, 8]))
        for a in ("x", "y"):  # the feedforward gains were drawn for a window of 4
            if kind == "pdff":
                g[f"kv_{a}"] *= g["win"] / 4
                g[f"ka_{a}"] *= (g["win"] / 4) ** 2
    return g


STARTS = (0, 40000, -5000, 1 << 26)
SCALES = (0, 1, 5, 50, 2000, 40000, 100000)
SEGMENT = st.tuples(
    st.integers(1, 30),                                            # ticks
    st.sampled_from(["hold", "ramp", "jump", "reverse"]),
    st.integers(-400, 400), st.integers(-400, 400),                # speed, counts a tick
    st.sampled_from(SCALES),                                      # position error scale, counts
)


@st.composite
def sequences(draw, max_segments: int = 12) -> np.ndarray:
    """(N, 4) int64 rows ref_x, ref_y, pos_x, pos_y."""
    segs = draw(st.lists(SEGMENT, min_size=1, max_size=max_segments))
    return build_rows(segs, draw(st.sampled_from(STARTS)), draw(st.integers(0, 2 ** 32 - 1)))



def seeded_sequence(seed: int, n_segments: int = 40) -> np.ndarray:
    """A long sequence fixed by seed (for the simulator runs, which take one sequence)."""
    rng = np.random.default_rng(seed)
    kinds = ("hold", "ramp", "jump", "reverse")
    segs = [(int(rng.integers(1, 31)), kinds[int(rng.integers(4))], int(rng.integers(-400, 401)),
             int(rng.integers(-400, 401)), SCALES[int(rng.integers(len(SCALES)))]) for _ in range(n_segments)]
    return build_rows(segs, 40000, seed)


def seeded_gains(kind: str, seed: int, tick_s: float = TICK_S) -> dict:
    """Gains fixed by seed, every one non-zero (a zero gain lets the compiler drop its term)."""
    if kind in NEURAL:
        return seeded_nn_params(kind, seed, CFG)
    rng = np.random.default_rng(seed)
    g = make_plain(kind)
    for key in g:
        g[key] *= float(rng.uniform(0.5, 2.0))
    return g


def make_plain(kind: str) -> dict:
    """Moderate gains of each kind (physical units, a 5 ms tick; the neural kinds: a seeded start)."""
    if kind in NEURAL:
        return seeded_nn_params(kind, 0, CFG)
    pid = dict(kp_x=2.0, ki_x=4.0, kd_x=0.02, kp_y=1.5, ki_y=3.0, kd_y=0.03)
    if kind == "pid":
        return pid
    if kind == "ccc":
        return {**pid, "kcp": 3.0, "kcd": 0.02}
    return dict(kp_x=2.0, kd_x=0.02, kv_x=0.02, ka_x=2e-4, kp_y=1.5, kd_y=0.03, kv_y=0.03, ka_y=3e-4)


def build_rows(segs, start: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    ref = np.array([start, start // 2], dtype=np.int64)
    v = np.zeros(2, dtype=np.int64)
    rows = []
    for n, what, vx, vy, scale in segs:
        if what == "jump":
            ref = ref + rng.integers(-60000, 60001, 2)
        elif what == "ramp":
            v = np.array([vx, vy])
        elif what == "reverse":
            v = -v
        else:
            v = np.zeros(2, dtype=np.int64)
        for _ in range(n):
            ref = ref + v
            err = rng.integers(-scale, scale + 1, 2) if scale else np.zeros(2, dtype=np.int64)
            rows.append([ref[0], ref[1], ref[0] - err[0], ref[1] - err[1]])
    return np.array(rows, dtype=np.int64)
