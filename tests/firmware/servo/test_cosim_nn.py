"""The neural controllers on the simulated Uno in closed loop (issue 29 item 4): chip = integer model
at every tick for the duties AND the weights' checksum (the runtime's nnik_servo_sum against checksum()), on random
params (weights anywhere up to their clamps, any learning rate) and random references; a model that
differs from the chip in one weight's lowest bit, invisible in every duty, is caught by the checksum
alone."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik.firmware.servo.build import build_firmware
from nnik.firmware.servo.cosim import run
from nnik.implementations.servo import NEURAL, make
from tests.conftest import require_tool
from tests.firmware.servo.chip_fixtures import references, shipped_cfg
from tests.implementations.servo.nn_params import nn_params, seeded_nn_params


@pytest.mark.parametrize("kind", NEURAL)
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_chip_duties_and_weights_equal_the_model(kind, data, tmp_path_factory):
    require_tool("avr-gcc")
    require_tool("simavr")
    cfg = shipped_cfg()
    params = data.draw(nn_params(kind))
    ref = data.draw(references(max_ticks=60))
    root = tmp_path_factory.mktemp(kind)
    ctl = make(kind, params, cfg)
    fw = build_firmware(ctl, cfg.tick_s, root)
    assert fw.symbols["nnik_servo_sum"] > 0
    tr = run(fw, cfg, ctl, ref, root / "run", start_counts=tuple(int(c) for c in ref[0]))
    bad = tr.mismatch_ticks
    assert tr.mismatches == 0, (f"tick {bad[0]}: chip {tr.chip_duty[bad[0]]} sum {tr.chip_sum[bad[0]]}, model "
                                f"{tr.model_duty[bad[0]]} sum {tr.model_sum[bad[0]]}")
    assert (tr.chip_sum == tr.model_sum).all() and (tr.model_sum == tr.model_sum & 0xFFFF).all()


@pytest.mark.parametrize("kind", NEURAL)
def test_the_checksum_catches_a_weight_no_duty_shows(kind, tmp_path):
    """The chip learns (its checksum moves); a model one LSB off in one master word (below the 16
    bits the forward pass uses) gives the same duties, and every tick mismatches on the checksum."""
    require_tool("avr-gcc")
    require_tool("simavr")
    cfg = shipped_cfg()
    params = seeded_nn_params(kind, 5, cfg)
    ref = np.concatenate([np.zeros((10, 2), np.int64), np.tile([6000, -4000], (80, 1))])
    fw = build_firmware(make(kind, params, cfg), cfg.tick_s, tmp_path / "fw")
    good = run(fw, cfg, make(kind, params, cfg), ref, tmp_path / "good")
    assert good.mismatches == 0 and len(set(good.chip_sum.tolist())) > 10  # the weights change as it learns
    off = {**params, "w1": [[list(r) for r in net] for net in params["w1"]]}
    off["w1"][0][0][0] += 1 if off["w1"][0][0][0] & 0xFFFF != 0xFFFF else -1
    bad = run(fw, cfg, make(kind, off, cfg), ref, tmp_path / "bad")
    assert (bad.chip_duty == bad.model_duty).all()
    assert bad.mismatches == len(ref) and (bad.chip_sum != bad.model_sum).all()
