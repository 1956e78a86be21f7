"""The controller on the simulated Uno in closed loop with the Python plant (issue 28 item 5):
chip = integer model at every tick on random references and random plants (hypothesis), fast
moves included; the chip's latched counts = the plant's (no edge lost) while the plant's top speed
is within what the encoder interrupt sustains; a wrong model is caught; the tick is refused when
Timer1 cannot make it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from nnik.errors import NnikError
from nnik.firmware.servo.build import tick_ocr1a
from nnik.firmware.servo.cosim import run
from nnik.implementations.servo import KINDS
from tests.dynamics.servo.plants import configs
from tests.firmware.servo.chip_fixtures import controller, firmware, references, shipped_cfg

TOP_COUNTS_S = 25_000  # plants up to 62.5 mm/s at 2.5 um/count: twice the DOMAIN class's free speed


@pytest.mark.parametrize("kind", KINDS)
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_chip_equals_model_on_random_plants_and_references(kind, data, tmp_path_factory):
    cfg = data.draw(configs(coulomb=True, stiction=data.draw(st.booleans()), backlash=data.draw(st.booleans())))
    assume(max(cfg.free_speed_counts_s(a) for a in range(2)) <= TOP_COUNTS_S)
    ref = data.draw(references())
    start = (data.draw(st.integers(-3000, 3000)), data.draw(st.integers(-3000, 3000)))
    root = tmp_path_factory.getbasetemp()
    fw = firmware(kind, cfg, root)
    tr = run(fw, cfg, controller(kind, cfg), ref + np.array(start), root / "run", start_counts=start)
    assert tr.mismatches == 0, f"tick {tr.mismatch_ticks[0]}: chip {tr.chip_duty[tr.mismatch_ticks[0]]} model {tr.model_duty[tr.mismatch_ticks[0]]}"
    assert tr.lost_counts == 0
    assert (tr.counts[0] == start).all()
    assert tr.cycles_max > 100 and (tr.tick_isr_cycles >= tr.ctl_cycles).all()


def test_fast_moves_run_the_encoder_interrupt_hard(tmp_path):
    """Full-duty steps on the shipped plant: many edges a tick, every one counted, chip = model."""
    cfg = shipped_cfg()
    n = 160
    ref = np.zeros((n, 2), np.int64)
    ref[:, 0] = 30000
    ref[:, 1] = -24000
    fw = firmware("pid", cfg, tmp_path)
    tr = run(fw, cfg, controller("pid", cfg), ref, tmp_path / "run")
    per_tick = np.abs(np.diff(tr.plant_counts, axis=0)).sum(axis=1)
    top = math.floor(sum(cfg.free_speed_counts_s(a) for a in range(2)) * cfg.tick_s)
    assert per_tick.max() >= 0.8 * top  # near the motors' free speed on both axes
    assert tr.enc_isrs.max() >= per_tick.max() // 2
    assert tr.mismatches == 0 and tr.lost_counts == 0
    assert (np.abs(tr.chip_duty) == cfg.duty_max).any()
    assert tr.load_pct_max > tr.ctl_cycles.max() / tr.period_cycles * 100


def test_a_wrong_model_is_caught(tmp_path):
    cfg = shipped_cfg()
    ref = np.tile([400, -300], (30, 1))
    fw = firmware("pdff", cfg, tmp_path)
    tr = run(fw, cfg, controller("pdff", cfg), ref, tmp_path / "run",
             model_duty=lambda k, d: (d[0] + (k == 17), d[1]))
    assert tr.mismatches == 1 and tr.mismatch_ticks.tolist() == [17]


def test_a_wrong_weight_checksum_is_caught(tmp_path):
    """The duties agree but the model's checksum is off at one tick: that tick mismatches. A
    fixed-gain controller's chip never sets nnik_servo_sum: the harness reads 0 (or finds no such
    variable: 0 too), as the model's checksum()."""
    cfg = shipped_cfg()
    ref = np.tile([400, -300], (30, 1))
    fw = firmware("ccc", cfg, tmp_path)
    tr = run(fw, cfg, controller("ccc", cfg), ref, tmp_path / "run", model_sum=lambda k, s: s + (k == 9))
    assert tr.mismatch_ticks.tolist() == [9] and (tr.chip_duty == tr.model_duty).all()
    assert (tr.chip_sum == 0).all() and tr.model_sum.tolist() == [int(k == 9) for k in range(30)]


@pytest.mark.parametrize("tick_s", [0.0, 1e-7, 0.0333, 0.05, 0.0050001])
def test_a_tick_timer1_cannot_make_is_refused(tick_s):
    with pytest.raises(NnikError, match="Timer1"):
        tick_ocr1a(tick_s)


def test_tick_timer_values():
    assert tick_ocr1a(0.005) == 9999 and tick_ocr1a(0.001) == 1999


class RunawayPlant:
    """A plant too fast for any encoder interrupt: `per_substep` counts every substep on X."""

    table_um = (0.0, 0.0)

    def __init__(self, substeps: int, per_substep: int):
        self.substeps, self.per, self.counts = substeps, per_substep, (0, 0)

    def step(self, duty):
        x0 = self.counts[0]
        rows = np.array([[x0 + self.per * (j + 1), 0] for j in range(self.substeps)], dtype=np.int64)
        self.counts = (int(rows[-1, 0]), 0)
        return rows


def test_lost_edges_are_seen(tmp_path):
    """Edges closer than the encoder interrupt can take: the chip's counts fall behind the plant's,
    the co-simulation says so, and chip = model still holds (the model sees the chip's counts)."""
    cfg = shipped_cfg()
    fw = firmware("pid", cfg, tmp_path)
    slow = run(fw, cfg, controller("pid", cfg), np.zeros((6, 2), np.int64), tmp_path / "slow",
               plant=RunawayPlant(cfg.substeps, 5))
    assert slow.lost_counts == 0  # 200 counts a tick: every edge counted
    fast = run(fw, cfg, controller("pid", cfg), np.zeros((6, 2), np.int64), tmp_path / "fast",
               plant=RunawayPlant(cfg.substeps, 1500))
    assert fast.lost_counts >= 4 and fast.mismatches == 0
    assert (fast.counts[1:, 0] < fast.plant_counts[1:, 0]).all()
