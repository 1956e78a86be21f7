"""datasets/xy_table.toml's plant, measured by running it: the default class's figures (DOMAIN:
about 25 mm/s free at 12 V, stall about 5.5 A, no-load 0.15-0.2 A, starts at about 1 V) and a
speed time constant in the tens of milliseconds, per axis; and the closed loop's plumbing."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from nnik.dynamics.servo.closed_loop import simulate
from nnik.dynamics.servo.plant import Plant
from nnik.machine.scenario import load_scenario
from tests.conftest import DATASETS

CFG = load_scenario(DATASETS / "xy_table.toml").servo


def full_duty_run(cfg, seconds: float):
    """Speed (rad/s) and current (A) at every substep from rest at full duty, both axes."""
    plant = Plant(cfg)
    w, i = [], []
    for _ in range(round(seconds / cfg.tick_s)):
        plant.step((cfg.duty_max, cfg.duty_max))
        w.append(np.stack([s[:, 1] for s in plant.last_states], 1))
        i.append(np.stack([s[:, 0] for s in plant.last_states], 1))
    return np.concatenate(w), np.concatenate(i), plant


def figures(cfg) -> dict:
    h = cfg.tick_s / cfg.substeps
    w, i, plant = full_duty_run(cfg, 1.0)
    c0 = np.array(plant.counts)
    for _ in range(200):  # one more second at full speed, counted by the encoder
        plant.step((cfg.duty_max, cfg.duty_max))
    free_mm_s = (np.array(plant.counts) - c0) * cfg.um_per_count / 1000.0
    blocked = replace(cfg, axes=tuple(replace(ax, j_kg_m2=ax.j_kg_m2 * 1e6) for ax in cfg.axes))
    _, ib, _ = full_duty_run(blocked, 0.02)  # a blocked rotor: the current settles, the speed stays ~0
    tau = [(np.argmax(w[:, a] >= (1 - math.exp(-1)) * w[-1, a]) + 1) * h for a in range(2)]
    return {"free_mm_s": free_mm_s, "no_load_a": i[-1], "stall_a": ib[-1], "tau_s": np.array(tau)}


def test_the_shipped_axes_have_the_default_class_figures():
    f = figures(CFG)
    assert np.all((f["free_mm_s"] > 23.0) & (f["free_mm_s"] < 27.0)), f
    assert np.all((f["stall_a"] > 4.8) & (f["stall_a"] < 6.0)), f
    assert np.all((f["no_load_a"] >= 0.15) & (f["no_load_a"] <= 0.2)), f
    assert np.all((f["tau_s"] >= 0.01) & (f["tau_s"] < 0.1)), f
    assert f["free_mm_s"][0] != f["free_mm_s"][1] and f["tau_s"][0] != f["tau_s"][1]  # the axes differ


@pytest.mark.parametrize("volts,moves", [(0.8, False), (1.3, True)])
def test_the_shipped_axes_start_at_about_one_volt(volts, moves):
    duty = round(volts / CFG.supply_v * CFG.duty_max)
    plant = Plant(CFG)
    for _ in range(100):
        plant.step((duty, duty))
    assert (plant.counts != (0, 0)) == moves and all((c != 0) == moves for c in plant.counts)


class Bang:
    """A test controller: full duty toward the reference."""

    kind = "bang"

    def __init__(self, dm):
        self.dm, self.resets, self.seen = dm, 0, []

    def reset(self):
        self.resets += 1

    def tick(self, ref, pos):
        self.seen.append(pos)
        return tuple(float(np.sign(r - p)) * self.dm * 2 for r, p in zip(ref, pos))  # saturated by the plant


def test_simulate_feeds_the_controller_the_counts_and_holds_its_saturated_duty():
    ref = np.zeros((300, 2), dtype=np.int64)
    ref[20:] = (2000, -1500)
    ctl = Bang(CFG.duty_max)
    tr = simulate(CFG, ctl, ref, substeps=True)
    assert ctl.resets == 1 and len(ctl.seen) == 300
    np.testing.assert_array_equal(tr.counts, np.array(ctl.seen))
    np.testing.assert_array_equal(tr.counts[1:], tr.substep_counts[:-1, -1])  # the last substep is the next tick
    assert np.abs(tr.duty).max() == CFG.duty_max and tr.saturated_fraction > 0.1
    assert np.all(tr.duty[:20] == 0)
    final = tr.counts[-1]
    assert abs(final[0] - 2000) < 200 and abs(final[1] + 1500) < 200
    np.testing.assert_allclose(tr.table_um, (tr.counts + 0.5) * CFG.um_per_count, atol=CFG.um_per_count)


def test_simulate_is_reproducible():
    t = np.arange(600) * CFG.tick_s
    ref = np.stack([4000 + 2000 * np.sin(2 * np.pi * t), 3000 + 2000 * np.cos(2 * np.pi * t)], 1).round()
    a, b = simulate(CFG, Bang(CFG.duty_max), ref, substeps=True), simulate(CFG, Bang(CFG.duty_max), ref, substeps=True)
    for f in ("counts", "duty", "table_um", "substep_counts"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
