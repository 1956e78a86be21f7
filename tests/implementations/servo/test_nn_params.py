"""The neural controllers' params: a seeded start is deterministic and JSON-serialisable; params()
carries the learnt weights (a controller made from them starts where the other stopped); the
generated header holds the initial weights; bad params are one NnikError line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nnik.errors import NnikError
from nnik.implementations.servo import NEURAL, make
from nnik.implementations.servo.c_check import model_duties
from nnik.implementations.servo.emit_c import servo_config_h
from nnik.implementations.servo.nn import formats as f
from nnik.implementations.servo.nn import initial_params, jacobian_q
from nnik.implementations.servo.nn.nn_vector import split_gains
from tests.implementations.servo.nn_params import SEED_J
from tests.implementations.servo.sequences import CFG, seeded_sequence


@pytest.mark.parametrize("kind", NEURAL)
def test_a_seeded_start_is_deterministic_and_json(kind):
    a = initial_params(kind, CFG, 3, jacobian=SEED_J)
    assert a == initial_params(kind, CFG, 3, jacobian=SEED_J) != initial_params(kind, CFG, 4, jacobian=SEED_J)
    assert json.loads(json.dumps(a)) == a
    assert a["jacobian"] == [round(1.0103 * 4096), round(0.6047 * 4096)]
    assert len(a["w1"]) == len(a["w2"]) == {"nn_axes": 2, "nn_vector": 1}[kind]


@pytest.mark.parametrize("kind", NEURAL)
def test_params_carry_the_learnt_weights(kind):
    ctl = make(kind, initial_params(kind, CFG, 1, jacobian=SEED_J, eta_shift=5), CFG)
    rows = seeded_sequence(2)[:80]
    model_duties(ctl, rows)
    learnt = ctl.params()
    assert learnt != ctl.p and json.loads(json.dumps(learnt)) == learnt
    again = make(kind, learnt, CFG)
    assert again.checksum() == ctl.checksum() and again.weight_norm() == ctl.weight_norm()
    assert again.tick((10, 10), (0, 0)) == make(kind, learnt, CFG).tick((10, 10), (0, 0))


@pytest.mark.parametrize("kind", NEURAL)
def test_the_header_holds_the_initial_weights(kind):
    ctl = make(kind, initial_params(kind, CFG, 2, jacobian=SEED_J), CFG)
    text = servo_config_h(ctl)
    arrays = ctl.c_arrays()
    assert len(arrays["NNIK_NN_W1_INIT"]) == 32 * len(ctl.nets) and len(arrays["NNIK_NN_W2_INIT"]) == 8 * len(ctl.nets)
    for name, values in arrays.items():
        body = text[text.index(f"#define {name} {{"):]
        body = body[body.index("{") + 1:body.index("}")]
        assert [int(v.strip().rstrip("L")) for v in body.replace("\\", "").split(",")] == values
    assert f"#define NNIK_CTL_{kind.upper()} 1" in text


def test_the_split_gains_favour_the_weaker_axis():
    cx, cy = split_gains([jacobian_q(1.0103), jacobian_q(0.6047)])
    assert cx == 256 and cy == round(256 * 4138 / 2477)
    with pytest.raises(NnikError, match="differ more than 16x"):
        split_gains([4096, 200])


@pytest.mark.parametrize("change, message", [
    ({"eta_shift": 28}, "eta_shift must be an integer in 0 .. 27"),
    ({"eta_shift": 1.5}, "eta_shift"),
    ({"in_shift": [0, 0, 0]}, "in_shift must be a list of 4"),
    ({"in_shift": [0, 0, 0, 13]}, r"in_shift\[3\]"),
    ({"jacobian": [40000, 1]}, r"jacobian\[0\]"),
    ({"w2": [[f.W2_LIM + 1] * 8] * 2}, r"w2\[0\]"),
    ({"w1": [[[0] * 4] * 7] * 2}, "w1"),
    ({"win": 3}, "win must be one of"),
    ({"speed": 1}, "unknown key 'speed'"),
])
def test_bad_params_are_one_error(change, message):
    p = {**initial_params("nn_axes", CFG, 0, jacobian=SEED_J), **change}
    with pytest.raises(NnikError, match=message) as e:
        make("nn_axes", p, CFG)
    assert "\n" not in str(e.value)


def test_bad_vector_params_and_missing_keys():
    p = initial_params("nn_vector", CFG, 0, jacobian=SEED_J)
    with pytest.raises(NnikError, match="both Jacobians must be > 0"):
        make("nn_vector", {**p, "jacobian": [4096, -4096]}, CFG)
    del p["w1"]
    with pytest.raises(NnikError, match="missing 'w1'"):
        make("nn_vector", p, CFG)
    with pytest.raises(NnikError, match="Q12 range"):
        jacobian_q(9.0)
    with pytest.raises(NnikError, match="is not tuned"):
        from nnik.implementations.servo.tune import tune
        tune("nn_axes", CFG, None, np.zeros((4, 2)), 3, 1)
