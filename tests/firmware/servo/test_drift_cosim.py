"""The drifting and the differing plants drive the chip as the nominal one does: cosim.run(plant=...)
takes them, chip = model at every tick, and the chip-driven plant moves exactly as the Python loop's
(closed_loop.simulate(plant=...)) with the same controller."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.dynamics.servo.closed_loop import simulate
from nnik.dynamics.servo.drift import JOB_DRIFT, DriftPlant, differing
from nnik.dynamics.servo.plant import Plant
from nnik.firmware.servo.cosim import run
from tests.firmware.servo.chip_fixtures import controller, firmware
from tests.firmware.servo.test_cosim import shipped_cfg


@pytest.mark.parametrize("kind, plant", [("nn_vector", "drift"), ("pid", "drift"), ("nn_axes", "differing")])
def test_the_chip_on_the_drifting_and_the_differing_plant(kind, plant, tmp_path):
    cfg = shipped_cfg()
    n = 240
    ref = np.zeros((n, 2), np.int64)
    ref[20:, 0], ref[20:, 1] = 4000, 2500  # a step, then a slow ramp on X
    ref[120:, 0] += np.arange(n - 120) * 6

    def make_plant():
        return DriftPlant(cfg, n, JOB_DRIFT, 4) if plant == "drift" else Plant(differing(cfg))

    fw = firmware(kind, cfg, tmp_path)
    tr = run(fw, cfg, controller(kind, cfg), ref, tmp_path / "run", plant=make_plant())
    assert tr.mismatches == 0 and tr.lost_counts == 0
    py = simulate(cfg, controller(kind, cfg), ref, plant=make_plant())
    assert np.array_equal(tr.plant_counts, py.counts)
    nominal = simulate(cfg, controller(kind, cfg), ref)
    assert not np.array_equal(nominal.counts, py.counts)  # the plant is not the nominal one
