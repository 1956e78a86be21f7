"""The sample loop's profile (nnik.bench.sample_profile) accounts for the busy pin's cycles: its
parts sum to the busy time the job's events record, and every part but planning runs on every
sample."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik import pipeline
from nnik.bench.sample_profile import profile_job
from nnik.firmware.gcode.simrun import read_events
from tests.firmware.gcode.conftest import require_chip

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"


def test_the_profile_sums_to_the_busy_pins_cycles(galvo_run, tmp_path):
    require_chip()
    pipeline.export(galvo_run)
    r = profile_job(galvo_run, JOBS / "l_path.gcode", "zvd", 1000, "atmega328p", tmp_path)
    _, _, busy, _ = read_events(tmp_path / "events.bin")
    pin = float((busy[:, 1] - busy[:, 0]).sum())
    total = sum(r["parts"].values())
    assert abs(total - pin) <= 0.01 * pin, (total, pin)
    per = {k: v / r["samples"] for k, v in r["parts"].items()}
    parts = ("the planner's sample", "the shaper and the step counts (out_sample)", "the segment queue", "the IK")
    assert all(per[k] > 50 for k in parts), per
    assert np.isclose(sum(r["functions"].values()), total)
