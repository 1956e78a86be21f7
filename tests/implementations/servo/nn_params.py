"""Random params for the neural controllers' tests: weights anywhere in their formats (up to the
clamps, so both clamps and saturation are reached), any learning rate, input shift and Jacobian."""

from __future__ import annotations

from hypothesis import strategies as st

from nnik.implementations.servo.nn import formats as f
from nnik.implementations.servo.nn import initial_params
from nnik.implementations.servo.nn.params import NETS

SEED_J = (1.0103, 0.6047)  # the seed's measured Jacobians (X, Y)


def _word(lim: int):
    # small words as often as large ones; the clamp itself and its neighbours reachable
    return st.one_of(st.integers(-lim, lim), st.integers(-(lim >> 8), lim >> 8), st.sampled_from([-lim, lim, 0]))


@st.composite
def nn_params(draw, kind: str) -> dict:
    n = NETS[kind]
    jac = draw(st.lists(st.integers(1 if kind == "nn_vector" else -f.I16, f.I16), min_size=2, max_size=2))
    if kind == "nn_vector":  # the split needs the axes within 16x of each other
        jac[1] = max(jac[1], (jac[0] + 15) // 16, 1)
        jac[0] = max(jac[0], (jac[1] + 15) // 16, 1)
    p = {"w1": [[[draw(_word(f.W1_LIM)) for _ in range(f.N_IN)] for _ in range(f.N_HID)] for _ in range(n)],
         "w2": [[draw(_word(f.W2_LIM)) for _ in range(f.N_HID)] for _ in range(n)],
         "eta_shift": draw(st.integers(0, f.ETA_MAX)), "jacobian": jac,
         "in_shift": draw(st.lists(st.integers(-f.IN_SHIFT_MAX, f.IN_SHIFT_MAX), min_size=4, max_size=4)),
         "w1_every": draw(st.sampled_from([1, 2, 4, 8]))}
    if kind == "nn_axes":
        p["win"] = draw(st.sampled_from([1, 2, 4, 8]))
    else:
        p["r_shift"] = draw(st.integers(0, 15))
    return p


def seeded_nn_params(kind: str, seed: int, cfg, eta_shift: int = 8) -> dict:
    """A seeded random start that learns visibly (a fast rate): weights change every tick."""
    return initial_params(kind, cfg, seed, jacobian=SEED_J, eta_shift=eta_shift)
