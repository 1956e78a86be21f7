"""nnik_gcode.c on the host with the real generated IK equals the Python model, segment for
segment and answer for answer, on the shipped jobs and on random lines (good and bad)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.firmware.gcode.host import run_engine_host
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.ik_oracle import ik_oracle
from nnik.firmware.gcode.parse import split_lines

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


@pytest.fixture(scope="module")
def corexy_lib(corexy_run, tmp_path_factory):
    pipeline.export(corexy_run)
    lib = tmp_path_factory.mktemp("lib") / "nnik_corexy"
    info = export_arduino(corexy_run, lib)
    return corexy_run, lib, info


def random_lines(n: int, seed: int) -> list[str]:
    """Moves within +-20 mm in every mode, arcs with exact centres, and a share of bad lines."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        k = rng.integers(0, 10)
        x, y = rng.uniform(-20, 20, 2)
        if k <= 3:
            out.append(f"G{rng.integers(0, 2)} X{x:.3f} Y{y:.4f} F{rng.uniform(100, 3000):.1f}")
        elif k == 4:
            out.append(f"G91 G1 X{rng.uniform(-2, 2):.5f} Y{rng.uniform(-2, 2):.2f}")
        elif k == 5:
            out.append(rng.choice(["G90", "G21", "G20 G0 X0.2 Y-0.3", "G21", "M400", "(comment) ; more"]))
        elif k == 6:  # an arc back to where it starts (a full turn) or a half turn
            i, j = rng.uniform(-5, 5, 2)
            out.append(f"G{rng.integers(2, 4)} I{i:.3f} J{j:.3f}")
            out.append("G90")
        else:
            out.append(rng.choice(["G1 Z1", "G2 X1", "G1 X1 I1", "G1 X--1", "G7", "X99999", "G1 X1 (x",
                                   "G1 F0", "G3 X0 Y0 I0 J0", "x" * 100]))
    return out


def compare(outdir, lib, info, lines):
    host = run_engine_host(lib, info["name"], lines)
    cfg = info["machine"]
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik_oracle(outdir))
    assert host["replies"] == plan.replies
    assert np.array_equal(host["start"], seg.steps[0])
    want = np.column_stack([seg.delta, seg.ticks, seg.ends_um]) if len(seg.ticks) else np.zeros((0, 5), np.int64)
    assert np.array_equal(host["segments"], want)
    return plan


@pytest.mark.parametrize("job", ["l_path.gcode", "circle.gcode", "star.gcode"])
def test_shipped_jobs(corexy_lib, job):
    outdir, lib, info = corexy_lib
    plan = compare(outdir, lib, info, split_lines((JOBS / job).read_bytes()))
    assert all(r == "ok" for r in plan.replies)


def test_random_lines_good_and_bad(corexy_lib):
    outdir, lib, info = corexy_lib
    lines = random_lines(300, seed=1)
    plan = compare(outdir, lib, info, lines)
    n_err = sum(r != "ok" for r in plan.replies)
    assert 20 < n_err < len(lines) - 100  # both kinds were exercised
    assert len(plan.ends) > 1000


def test_r_arcs_at_the_limits_and_random(corexy_lib):
    """R arcs under UBSan/ASan: 1 um chords with R = 9999 in (the largest shift and root), R
    arcs at the 2|R| tolerance and beyond, and 200 random ones, short and long, both ways."""
    outdir, lib, info = corexy_lib
    rng = np.random.default_rng(2)
    lines = ["G20 G91 G2 X0.00004 Y-0.00004 R9999", "G3 X-0.00004 R9999.9", "G2 X0.00003 Y0.0001 R-0.0001",
             "G21 G90 G0 X0 Y0", "G2 X0.001 R0.001", "G3 X0.002 R-0.0005", "G2 X5 R2.5", "G3 X0 R2.499",
             "G3 X5 R2.49", "G2 X1 I1 R1", "G1 X1 R1", "G2 R5", "G3 Y5 R0"]
    for _ in range(200):
        x, y = rng.uniform(-20, 20, 2)
        lines.append(f"G{rng.integers(2, 4)} X{x:.3f} Y{y:.3f} R{rng.uniform(-30, 30):.3f} F9000")
    plan = compare(outdir, lib, info, lines)
    ok = sum(r == "ok" for r in plan.replies)
    assert 100 < ok < len(lines) - 50  # R arcs drawn and R arcs refused
