"""A small version of each of nnik.bench.servo's measurements (not timed: the cycles are
deterministic): cycles per tick and CPU % at 5 ms and 1 ms on a short steps job, the printed line,
and the edge-rate search (sustained at the rate found, not one cycle faster)."""

from __future__ import annotations

import io
import json
from pathlib import Path

from nnik.bench.servo import BUDGETS, GAINS, at_tick, load_gains, measure_kind, report
from nnik.firmware.servo.build import CLOCK_HZ
from nnik.firmware.servo.edge_rate import edge_run, max_edge_rate
from nnik.machine.scenario import load_scenario
from tests.conftest import require_tool
from tests.implementations.servo.nn_params import seeded_nn_params

SCENARIO = Path(__file__).resolve().parents[2] / "datasets" / "xy_table.toml"


def test_cycles_and_load_at_5_and_1_ms(tmp_path):
    require_tool("avr-gcc")
    require_tool("simavr")
    cfg = load_scenario(SCENARIO).servo
    r5 = measure_kind("pid", GAINS["pid"], cfg, tmp_path, seconds_each=0.3)
    r1 = measure_kind("pid", GAINS["pid"], at_tick(cfg, 0.001), tmp_path, seconds_each=0.3)
    for r in (r5, r1):
        assert r["mismatches"] == 0 and r["lost"] == 0
        assert 100 < r["cycles_max"] <= 1600  # the PID's budget: 800 per axis
        assert r["enc_isr_max"] > 0 and max(r["top_edges_s"]) > 1000
    # the same work in a fifth of the time: the load grows with the tick rate
    assert r1["load_pct"] > r5["load_pct"]
    assert abs(r5["load_pct"] - (r5["tick_isr_max"] + r5["enc_isr_max"]) / 80000 * 100) < 2.0


def test_edge_rate_search(tmp_path):
    require_tool("avr-gcc")
    require_tool("simavr")
    cfg = load_scenario(SCENARIO).servo
    fw = measure_kind("pid", GAINS["pid"], cfg, tmp_path, seconds_each=0.05)["fw"]
    best = max_edge_rate(fw, tmp_path / "e", ticks=3)
    assert best.sustained and best.edges > 0
    faster = edge_run(fw, round(CLOCK_HZ / best.rate) - 1, 3, tmp_path / "e")
    assert not faster.sustained
    slow = edge_run(fw, 4000, 3, tmp_path / "e")
    assert slow.sustained and slow.lost == 0 and slow.awake_max < best.awake_max


def test_report_prints_the_issue_line(tmp_path):
    require_tool("avr-gcc")
    require_tool("simavr")
    buf = io.StringIO()
    cfg = load_scenario(SCENARIO).servo
    gains = {**GAINS, "nn_vector": seeded_nn_params("nn_vector", 1, cfg)}
    report(SCENARIO, seconds_each=0.05, edge_ticks=2, out=buf, gains=gains)
    text = buf.getvalue()
    assert text.count("controller cycles per tick: max ") == 2 * len(GAINS) + 1  # a neural one at 5 ms only
    assert "tick 1 ms" in text and "tick 5 ms" in text and "edges/s per axis" in text
    (nn,) = [ln for ln in text.splitlines() if ln.startswith("nn_vector")]
    assert "(budget 7,000: " in nn and ("% (within 50 %" in nn or "% (OVER 50 %" in nn)
    assert "mismatch 0 (checksum 0)" in nn and "flash " in nn and "RAM " in nn


def test_a_neural_controller_at_top_speed(tmp_path):
    """The neural controllers on the seed's steps: chip = model (duties and weights), the encoder
    interrupts running, the controller's cycles and the tick's load measured."""
    require_tool("avr-gcc")
    require_tool("simavr")
    cfg = load_scenario(SCENARIO).servo
    for kind in ("nn_axes", "nn_vector"):
        r = measure_kind(kind, seeded_nn_params(kind, 1, cfg), cfg, tmp_path, seconds_each=0.3)
        assert r["mismatches"] == 0 and r["checksum_mismatches"] == 0 and r["lost"] == 0
        assert r["cycles_max"] > BUDGETS["pid"] and r["enc_isr_max"] > 0 and max(r["top_edges_s"]) > 1000
        assert r["load_pct"] * 80000 / 100 > r["cycles_max"]  # the load holds the controller and the encoders
        assert 0 < r["ram"] <= 2048 and r["flash"] > 0


def test_gains_from_a_run_dir(tmp_path):
    """--gains: a run's servo/gains.json (every kind there, nothing pretrained again)."""
    cfg = load_scenario(SCENARIO).servo
    stored = {**GAINS, "nn_axes": seeded_nn_params("nn_axes", 3, cfg), "nn_vector": seeded_nn_params("nn_vector", 3, cfg)}
    (tmp_path / "servo").mkdir()
    (tmp_path / "servo" / "gains.json").write_text(json.dumps({"chosen": "pid", "gains": stored}))
    assert load_gains(load_scenario(SCENARIO), tmp_path) == stored
