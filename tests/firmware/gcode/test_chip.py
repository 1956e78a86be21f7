"""The library on the simulated Uno: Arduino AVR core + simavr. The self-test passes, the G-code
firmware fits, and every step it emits for each shipped job equals the Python model's.

To keep the simulated time short, the step comparisons run the shipped jobs at four times their
feed (the same paths; `nnik job` runs them as shipped); one job runs as shipped end to end."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.machine.data import exact_targets
from nnik.firmware.gcode import chip
from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.job.open_loop import run_job
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.gcode.reader import split_lines
from nnik.firmware.gcode.steps import chip_events, model_events
from tests.firmware.gcode.conftest import require_chip

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


@pytest.fixture(autouse=True)
def toolchain():
    require_chip()


def exact_min_events(run, plan, cfg) -> int:
    """A lower bound on a job's step events that follows from the scenario, not the trained model.

    Cut the path into k pieces at segment ends. The model's pre-rounding error is < 0.5 (asserted),
    so each rounded command is within 1 of the exact IK, and a piece whose exact IK moves by D
    makes at least |D| - 2 steps on that motor. Each k gives a bound; the best of a few is kept."""
    scn = pipeline.load_pair(run)[0].scenario
    assert max(pipeline.load_metrics(run)["fixed"]["max_abs"]) < 0.5
    ends = np.concatenate([[[0, 0]], np.asarray(plan.ends, dtype=np.int64).reshape(-1, 2)])
    exact = exact_targets(scn, (ends + np.asarray(cfg.origin_um)) / 1000.0)
    bounds = []
    for pieces in (1, 2, 4, 8, 16):
        cut = exact[np.unique(np.linspace(0, len(ends) - 1, pieces + 1).astype(int))]
        bounds.append(np.maximum(np.abs(np.diff(cut, axis=0)) - 2, 0).sum())
    return int(max(bounds))


def faster(lines: list[str], k: int = 4) -> list[str]:
    return [re.sub(r"F(\d+)", lambda m: f"F{int(m.group(1)) * k}", ln) for ln in lines]


@pytest.mark.parametrize("scenario", ["galvo_cba2012", "corexy_nonlinear"])
@pytest.mark.parametrize("job", ["l_path", "circle", "star"])
def test_every_step_of_every_job_matches(firmware, scenario, job):
    run, lib, fw, ik, work = firmware[scenario]
    lines = faster([ln.decode('latin-1') for ln in split_lines((JOBS / f"{job}.gcode").read_bytes())])
    cfg = lib["machine"]
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik)
    want = model_events(seg)
    res = chip.run_firmware(fw, lines, work, 2.0 + 1.5 * seg.ticks.sum() / cfg.tick_hz)
    assert res.state == "done"
    assert [t for _, t in res.replies[1:]] == plan.replies == ["ok"] * len(lines)
    assert len(res.marks) == len(seg.ticks)
    got = chip_events(res.steps, res.marks, CLOCK_HZ // cfg.tick_hz)
    assert len(want) >= exact_min_events(run, plan, cfg) > 0 and got.shape == want.shape
    assert np.array_equal(got, want)
    assert fw.flash_bytes <= chip.FLASH_BYTES and fw.ram_bytes <= chip.RAM_BYTES - 256  # the stack keeps 256 B (the brief)


@pytest.mark.parametrize("scenario", ["galvo_cba2012", "corexy_nonlinear"])
@pytest.mark.parametrize("job", ["l_path", "circle", "star"])
def test_every_step_matches_with_zvd_shaping(zvd_firmware, scenario, job):
    """The same with the ZVD shaper (40 Hz, zeta 0.1) on the chip: every step, every segment."""
    from tests.firmware.gcode.conftest import run_both

    entry = zvd_firmware[scenario]
    cfg = entry[1]["machine"]
    assert cfg.shaper == "zvd" and cfg.shaper_ram_bytes <= 256
    plan, seg, res = run_both(entry, faster([ln.decode('latin-1') for ln in split_lines((JOBS / f"{job}.gcode").read_bytes())]))
    assert np.abs(seg.ends_um - seg.planned_um).max() > 0  # the shaper moved the samples
    assert entry[2].ram_bytes <= chip.RAM_BYTES - 256


@pytest.mark.parametrize("job", ["l_path", "circle"])
def test_every_step_matches_with_a_hump_ei_shaper_per_axis(hump_firmware, job):
    """3HUMP_EI on X and 2HUMP_EI on Y (up to 10 and 8 taps: the largest shapers) on the
    Uno: every step and segment equals the model's, and the build fits with 256 B of stack."""
    from tests.firmware.gcode.conftest import run_both

    cfg = hump_firmware[1]["machine"]
    assert cfg.shaper == "3hump_ei/2hump_ei" and max(len(a) for a, _ in cfg.shaper_taps) >= 8
    plan, seg, res = run_both(hump_firmware, faster([ln.decode('latin-1') for ln in split_lines((JOBS / f"{job}.gcode").read_bytes())]))
    assert np.abs(seg.ends_um - seg.planned_um).max() > 0
    fw = hump_firmware[2]
    assert fw.flash_bytes <= chip.FLASH_BYTES and fw.ram_bytes <= chip.RAM_BYTES - 256


def test_shipped_job_end_to_end_with_selftest_rate_and_plot(firmware):
    run = firmware["corexy_nonlinear"][0]
    res = run_job(run, JOBS / "l_path.gcode", use_chip=True)
    c = res["chip"]
    assert c["selftest_pass"], c["selftest"]
    assert c["steps_equal"] and c["replies_equal"] and c["steps"] == res["steps"] > 3000
    cps = c["cycles_per_sample"]
    assert 1000 < cps["mean"] <= cps["max"] < 200_000
    # the sample loop's share of the CPU at 1 kHz samples, with the MLP as the IK (2,240 cycles a
    # call on this machine): the goal is <= 30 % (docs/motion.md; measured per build by nnik.bench.motion)
    assert 0.05 < c["cpu_sample_loop"] <= 0.45, c["cpu_sample_loop"]
    m = res["motion"]
    assert m["overspeed_samples"] == 0 and 0 < m["peak_step_rate_hz"] <= m["step_rate_limit_hz"]
    assert c["motion_s"] == pytest.approx(m["job_s"], abs=2e-3)  # the chip's idle time: the model's job time
    assert Path(res["png"]).stat().st_size > 10_000
    assert res["contour_um"]["max"] >= res["chord_um"]["max"]
    # the step counts rebuilt from the pins end where the IK puts the L's last corner
    rows = np.loadtxt(c["steps_csv"], delimiter=",", skiprows=1, dtype=np.int64)
    origin = np.asarray(firmware["corexy_nonlinear"][1]["machine"].origin_um)
    end, _ = firmware["corexy_nonlinear"][3](origin[None, :] + [[10_000, 10_000]])
    for m in range(2):
        assert rows[rows[:, 1] == m][-1, 3] == end[0, m]


def test_bad_lines_get_the_same_error_on_the_chip(firmware):
    run, lib, fw, _, work = firmware["corexy_nonlinear"]
    lines = ["G1 X1 F3000", "G1 A2", "G2 X5 Y5 I1", "G1 X" + "1" * 100, "G7", "G1 X1.1234567", "G1 Y1", "#1=2",
             "G38.2 Z-1", "M104 S200", "G1 X1 *1", "M400"]
    res = chip.run_firmware(fw, lines, work, 5.0)
    got = [t for _, t in res.replies if not t.startswith(("nnik ", "Grbl ", "["))]
    want = interpret(lines, lib["machine"]).replies
    assert got == want
    assert want == ["ok", "error:20", "error:33", "error:11", "error:20", "ok", "ok", "error:41", "error:43", "ok",
                    "error:40", "ok"]


def test_arduino_mk_builds_the_selftest_that_passes(firmware, tmp_path):
    """The library as a user builds it: Debian's arduino-mk over the Arduino core."""
    import shutil
    import subprocess

    mk = Path("/usr/share/arduino/Arduino.mk")
    if not mk.is_file() or shutil.which("make") is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("arduino-mk not installed")
        pytest.skip("arduino-mk not installed (run scripts/install_toolchains.sh)")
    run, lib, _, _, _ = firmware["galvo_cba2012"]
    libdir = tmp_path / "libraries" / "my_nnik"
    export_arduino(run, libdir)
    ex = libdir / "examples" / "galvo_cba2012_selftest"
    r = subprocess.run(["make", "-s"], cwd=ex, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-500:]
    elf = next((ex / "build-uno").glob("*.elf"))
    res = chip.run_firmware(chip.Firmware(elf, 0, 0), [], tmp_path, 5.0)
    assert res.state == "halted"
    assert [t for _, t in res.replies][-1].startswith("PASS 64 vectors, cycles per call: mean ")
