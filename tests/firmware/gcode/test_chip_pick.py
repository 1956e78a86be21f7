"""The G-code firmware with a non-MLP pick as its IK: the chip steps exactly as the Python model.

The galvo's lut pick once wrote a call-saved register it had not declared (movw r12 without
r13): the self-test's 64 vectors stayed bit-exact, but the sketch's feed, held in r12-r15
across the IK call, lost a byte and every segment ran 255 ticks instead of 250. Only a job on
the chip shows that. The job runs at twice its feed (the same path) to keep it short; at four
times (test_chip's speed-up) that corrupted feed still rounded to the same ticks."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.firmware.gcode import chip
from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.gcode.reader import split_lines
from nnik.firmware.gcode.steps import chip_events, model_events
from nnik.firmware.ik_oracle import ik_oracle, ik_sources, picked_implementation
from tests.firmware.gcode.test_chip import JOBS, faster, toolchain  # noqa: F401 (autouse: skip without the toolchain)


def test_lut_pick_steps_like_the_python_model(galvo_run, tmp_path):
    run = Path(shutil.copytree(galvo_run, tmp_path / "run", ignore=shutil.ignore_patterns("job", "report")))
    pipeline.select(run, progress=False, families=["lut"], target={"max_error": 0.05})
    impl = picked_implementation(run)
    assert impl is not None and impl.family == "lut"
    assert ik_sources(run, impl.problem.name) == run / pipeline.C_DIR

    lib = export_arduino(run, tmp_path / "lib")
    fw = chip.build_sketch(tmp_path / "lib", f"{lib['name']}_gcode", tmp_path / "build", {"NNIK_GRBL_QUIET_MS": "0", "NNIK_GRBL_PAUSE_RESUMES": "1"})
    lines = faster([ln.decode('latin-1') for ln in split_lines((JOBS / "l_path.gcode").read_bytes())], 2)
    cfg = lib["machine"]
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik_oracle(run))
    want = model_events(seg)
    res = chip.run_firmware(fw, lines, tmp_path / "build", 2.0 + 1.5 * seg.ticks.sum() / cfg.tick_hz)
    assert res.state == "done"
    assert [t for _, t in res.replies[1:]] == plan.replies == ["ok"] * len(lines)
    # segments last the ticks the model gives them (the feed survived the IK call) ...
    tick = CLOCK_HZ // cfg.tick_hz
    assert len(res.marks) == len(seg.ticks)
    assert np.array_equal(np.rint(np.diff(res.marks) / tick).astype(np.int64), seg.ticks[:-1])
    # ... and every step falls on the model's tick
    got = chip_events(res.steps, res.marks, tick)
    assert len(want) > 10 and got.shape == want.shape
    assert np.array_equal(got, want)
