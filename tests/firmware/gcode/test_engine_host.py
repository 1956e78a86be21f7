"""nnik_gcode.c (with nnik_plan.c and nnik_shaper.c) on the host with the real generated IK equals
the Python model, segment for segment and answer for answer, on the shipped jobs and on random
lines (good and bad), with and without each input shaper."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.firmware.gcode.host import run_engine_host
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.ik_oracle import ik_oracle
from nnik.firmware.gcode.reader import split_lines
from tests.firmware.gcode.random_gcode import random_lines as dialect_lines

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


@pytest.fixture(scope="module")
def corexy_lib(corexy_run, tmp_path_factory):
    pipeline.export(corexy_run)
    lib = tmp_path_factory.mktemp("lib") / "nnik_corexy"
    info = export_arduino(corexy_run, lib)
    # random walks leave the travel: the soft limits (ALARM:2, then error:9) have their own test
    from dataclasses import replace

    return corexy_run, lib, {**info, "machine": replace(info["machine"], bounds_um=None)}


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
            out.append(f"G91 G{rng.integers(2, 4)} X0 Y0 I{i:.3f} J{j:.3f}")  # a full turn (grbl: X Y written)
            out.append("G90")
        else:
            out.append(rng.choice(["G1 Z1", "G2 X1", "G1 X1 I1", "G1 X--1", "G7", "X1234567890", "G1 X1 (x",
                                   "G1 F0", "G3 X0 Y0 I0 J0", "x" * 100]))
    return out


def compare(outdir, lib, info, lines, cfg=None):
    cfg = cfg or info["machine"]
    host = run_engine_host(lib, info["name"], lines, defines=cfg.defines())
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik_oracle(outdir))
    assert host["replies"] == plan.replies
    assert np.array_equal(host["start"], seg.steps[0])
    want = (np.column_stack([seg.delta, seg.ticks, seg.ends_um, seg.duty]) if len(seg.ticks)
            else np.zeros((0, 6), np.int64))
    assert np.array_equal(host["segments"], want)
    assert host["overspeed"] == seg.overspeed
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


@pytest.mark.parametrize("setting", ["laser", "pen_z", "servo_m300", "marlin_e", "fitted", "soft_limits", "uno", "none"])
def test_the_whole_dialect_equal_on_the_host(corexy_lib, setting):
    """Every word class (tests/firmware/gcode/random_gcode.py: modes, offsets, G10/G28/G30/G53/G92,
    arcs in every plane, G5, G93, noted setup codes, checksums, refusals), with each tool rule,
    Marlin's flavour, the job's frame, soft limits and the Uno's build options: host C = model."""
    from dataclasses import replace

    from nnik.firmware.config import FEATURES, UNO_FEATURES

    outdir, lib, info = corexy_lib
    base = replace(info["machine"], features=FEATURES, bounds_um=None)
    cfg = {"laser": base, "pen_z": replace(base, tool="pen", pen_z_um=100),
           "servo_m300": replace(base, tool="servo", rule="m300"),
           "marlin_e": replace(base, tool="pen", rule="e", marlin=True),
           "fitted": replace(base, scale_q16=40000, shift_um=(1234, -5678)),
           "soft_limits": replace(base, bounds_um=((-40000, -40000), (40000, 40000))),
           "uno": replace(base, features=UNO_FEATURES), "none": replace(base, tool="none")}[setting]
    alarms = 0
    for seed in range(3):
        g5_then_dwell = ["G5 I1 J0 P-1 Q0 X3 Y1", "G4 P-1"] if seed == 0 else []  # a G5 offset, never a dwell
        plan = compare(outdir, lib, info, g5_then_dwell + dialect_lines(150, seed, marlin=cfg.marlin), cfg)
        if "ALARM:2" in plan.replies:  # then every G-code line is locked out, as grbl's alarm
            k = plan.replies.index("ALARM:2")
            assert set(plan.replies[k + 1:]) <= {"error:9", "error:39", "error:40", "error:11", "ok", "$"}
            alarms += 1
        else:
            assert plan.replies.count("ok") > 100 and len(set(plan.replies)) > 5
    assert (alarms > 0) == (setting == "soft_limits")


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


def with_checksum(line: str) -> str:
    x = 0
    for c in line.encode("latin-1"):
        x ^= c
    return f"{line}*{x}"


def test_grbl_words_equal_on_the_host(corexy_lib):
    """N numbers and checksums (good and bad), modal words, G92 (also in G91 and inches), G28 with
    and without axes, G28.1, G4 dwells, M2/M30, M0 and M1, then 200 random lines mixing them with
    moves and arcs."""
    from dataclasses import replace

    from nnik.firmware.config import FEATURES

    outdir, lib, info = corexy_lib
    info = {**info, "machine": replace(info["machine"], features=FEATURES, bounds_um=None)}
    lines = [with_checksum("N1 G17 G21 G90 G40 G49 G80 G94 G54 G64"), "N2 G1 X1 Y1 F900*0", "N3 G18", "G93 G1 X1",
             "N4 G0 X5 Y-3", with_checksum("N5 G92 X0 Y0"), "G1 X2 Y2", "G91 G92 X1", "G1 X1 Y-1", "G20 G92 Y0.1",
             "G21 G90 G2 X4 Y0 I1 J-1", "G4 P0.25", "G4 P0", "G4 P-1", "G28 X1", "G28", "G91 G28 Y2", "G28.1",
             "G92", "G92 X1 G1", "M0", "M1", "M30", "X1 Y1", "G4 P1.0004", "M2", "N99999999 G0 X0 Y0 *12 x"]
    rng = np.random.default_rng(3)
    for _ in range(200):
        x, y = rng.uniform(-15, 15, 2)
        k = rng.integers(0, 8)
        if k == 0:
            lines.append(f"G92 X{x:.3f}" + (f" Y{y:.3f}" if rng.integers(0, 2) else ""))
        elif k == 1:
            lines.append(f"G4 P{rng.uniform(0, 0.3):.4f}")
        elif k == 2:
            lines.append(rng.choice(["G28", f"G28 X{x:.2f}", f"G91 G28 Y{y:.2f}", "G90", "M30", "M2"]))
        elif k == 3:
            lines.append(with_checksum(f"N{rng.integers(0, 10**8)} G1 X{x:.3f} Y{y:.3f}"))
        elif k == 4:
            lines.append(f"G{rng.integers(2, 4)} X{x:.3f} Y{y:.3f} R{rng.uniform(-20, 20):.3f} F{rng.uniform(300, 3000):.0f}")
        elif k == 5:
            lines.append(rng.choice(["G18", "G41", "G55", "G61", "M0", "G4", "N1 G1 X1*1", "G1 X1 P1", "G92 G0 X1"]))
        else:
            lines.append(f"G{rng.integers(0, 2)} X{x:.3f} Y{y:.3f}")
    plan = compare(outdir, lib, info, lines)
    assert plan.replies[:4] == ["ok", "error:40", "ok", "error:22"]  # G18 is a plane; G93 needs F on each move
    assert plan.replies[13] == "error:4"  # G4 P-1
    assert plan.replies[17:22] == ["ok", "error:26", "error:24", "ok", "ok"]  # G28.1; G92 without axes; with G1
    assert plan.replies[26] == "error:39"  # '*12 x': a malformed checksum
    assert sum(d > 0 for d in plan.dwell) > 15 and sum(r != "ok" for r in plan.replies) > 20


def tool_lines(n: int, seed: int, pen: bool) -> list[str]:
    """Moves, arcs, rapids, dwells and the tool's words: M3/M4/M5 with S (above $30 too) on
    lasers, Z up/down (absolute, relative, inch) on pens; some bad tool lines."""
    rng = np.random.default_rng(seed)
    out = ["G21 G90 F2400"]
    for _ in range(n):
        x, y = rng.uniform(-10, 10, 2)
        k = rng.integers(0, 9)
        if k <= 2:
            out.append(f"G{rng.integers(0, 2)} X{x:.3f} Y{y:.3f}" + (f" F{rng.uniform(200, 9000):.0f}" if k == 2 else ""))
        elif k == 3:
            out.append(f"G{rng.integers(2, 4)} X{x:.3f} Y{y:.3f} R{rng.uniform(-15, 15):.3f}")
        elif k == 4:
            out.append(rng.choice([f"G4 P{rng.uniform(0, 0.05):.3f}", "M2", "G28", "M30", "G91", "G90"]))
        elif k in (5, 6) and pen:
            out.append(rng.choice([f"G0 Z{rng.uniform(-2, 5):.2f}", "G1 Z-1", "G0 Z5", f"G1 X{x:.2f} Z{rng.uniform(-1, 1):.2f}",
                                   "G20 G1 Z0.1", "G21", "G91 G0 Z1", "G90 Z-0.5", "M3 S500", "M5", "G4 Z1 P1"]))
        elif k in (5, 6):
            out.append(rng.choice([f"M3 S{rng.uniform(0, 1200):.1f}", f"M4 S{rng.integers(0, 1000)}", "M5", "S300", "M4",
                                   f"G1 X{x:.3f} M3 S{rng.integers(0, 1000)}", "M3 M5", "S-1", "G1 Z1", "M3"]))
        else:
            out.append(f"G91 G1 X{rng.uniform(-0.8, 0.8):.3f} Y{rng.uniform(-0.8, 0.8):.3f}")
            out.append("G90")
    return out


@pytest.mark.parametrize("tool", ["laser", "pen", "servo"])
def test_tool_output_equal_on_the_host(corexy_lib, tool):
    """Every segment's duty on D11, from the engine's C with the tool's macros, equals the model's."""
    from dataclasses import replace

    outdir, lib, info = corexy_lib
    cfg = replace(info["machine"], tool=tool, pen_z_um=250)
    plan = compare(outdir, lib, info, tool_lines(250, seed=4, pen=tool != "laser"), cfg)
    seg = plan_steps(plan, cfg, ik_oracle(outdir))
    duties = set(seg.duty.tolist())
    if tool == "laser":
        assert len(duties) > 20  # M3 powers, M4 scaled below them, off
        assert "error:4" in plan.replies  # S-1: a negative value
    else:
        assert duties == {cfg.pen_duty(True), cfg.pen_duty(False)}
    assert sum(plan.dwell) > 0 and sum(1 for d in plan.dwell if d == 1) > 3  # tool changes at rest


# every kind on both axes, and per axis as a [shaper] table gives it (3HUMP_EI: 9 and 10 taps)
SHAPERS = ("none", "zv", "mzv", "zvd", "ei", "2hump_ei", "3hump_ei", "3hump_ei/mzv", "none/2hump_ei")


def shaped_cfg(cfg, kind: str, f_hz=(40.0, 33.0), zeta=(0.1, 0.07)):
    from dataclasses import replace

    from nnik.firmware.config import axis_shapers

    table = {"type": tuple(kind.split("/")), "freq_hz": f_hz, "damping": zeta, "label": kind} if "/" in kind else None
    taps, designs = axis_shapers(kind, None if table else {"f_hz": f_hz, "zeta": zeta}, table, cfg.sample_hz)
    return replace(cfg, shaper=kind, shaper_taps=taps, shaper_design=designs)


@pytest.mark.parametrize("kind", SHAPERS)
@pytest.mark.parametrize("job", ["l_path.gcode", "circle.gcode", "star.gcode", "lasergrbl_raster.gcode"])
def test_shipped_jobs_with_each_shaper(corexy_lib, kind, job):
    outdir, lib, info = corexy_lib
    lines = split_lines((JOBS / job).read_bytes())
    cfg = shaped_cfg(info["machine"], kind)
    plan = compare(outdir, lib, info, lines, cfg)
    assert all(r == "ok" for r in plan.replies)


EXAMPLES = int(__import__("os").environ.get("NNIK_HYPOTHESIS_EXAMPLES", "10"))


@pytest.mark.parametrize("kind", SHAPERS)
def test_random_jobs_with_each_shaper_and_planner_setting(corexy_lib, kind):
    """hypothesis draws grbl-dialect jobs (the chip test's strategy) and planner settings (per-axis
    acceleration, junction deviation, max feed, sample rate, queue length); the host C equals the
    model bit for bit."""
    from dataclasses import replace

    from hypothesis import HealthCheck, given, note, settings
    from hypothesis import strategies as st

    from tests.firmware.gcode.test_gcode_hypothesis import jobs

    outdir, lib, info = corexy_lib

    @settings(max_examples=EXAMPLES, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(lines=jobs(), ax=st.integers(100, 15000), ay=st.integers(100, 15000), jd=st.integers(1, 200),
           feed=st.integers(600, 9000), hz=st.sampled_from([500, 1000, 2000]), n=st.integers(2, 16))
    def check(lines, ax, ay, jd, feed, hz, n):
        feed = min(feed, ((1 << 24) - 1) * 60 * hz // 65536 // 1000)  # speeds below 256 um per sample
        cfg = replace(info["machine"], accel_um_s2=(ax * 1000, ay * 1000), junction_dev_um=jd,
                      max_feed_um_min=feed * 1000, sample_hz=hz, plan_blocks=n, shaper="none", shaper_taps=())
        # the longest shapers (3hump_ei spans two periods) fit the 512 B budget at 2 kHz from 50 Hz up
        cfg = shaped_cfg(cfg, kind, f_hz=(60.0, 50.0) if hz >= 2000 else (40.0, 33.0) if hz >= 1000 else (40.0, 50.0))
        note("\n".join(lines))
        compare(outdir, lib, info, lines, cfg)

    check()
