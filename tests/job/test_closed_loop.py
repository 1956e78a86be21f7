"""`nnik run datasets/xy_table.toml` and `nnik job OUTDIR JOB.gcode` on the DC-servo xy_table, end to
end through the command line: the run identifies, tunes, runs the seed's tests and names the
default controller; the job runs closed loop in Python and on the simulated Uno (chip = model,
`mismatch 0`), and a job outside the strokes is refused unless --fit is given."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
JOBS = ROOT / "datasets" / "jobs"
KINDS = ("pid", "pdff", "ccc", "nn_axes", "nn_vector")


def nnik(*args, cwd=ROOT) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "nnik", *map(str, args)], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=1200)


@pytest.fixture(scope="module")
def xy_run(session_runs, tmp_path_factory) -> tuple[Path, subprocess.CompletedProcess]:
    """`nnik run datasets/xy_table.toml` from the root of a fresh copy, as docs/closed_loop.md runs it
    (once per session for both, tests/shared_run.py): this module's own copy of its output (the
    tests write into it), and the command's stdout."""
    built, r = session_runs.run("nnik run datasets/xy_table.toml", "build/xy_table")
    assert r.returncode == 0, r.stderr[-2000:]
    out = tmp_path_factory.mktemp("xy") / "xy_table"
    shutil.copytree(built, out)
    return out, r


def test_nnik_run_identifies_tunes_runs_the_seeds_tests_and_names_the_default(xy_run):
    out, r = xy_run
    gains = json.loads((out / "servo" / "gains.json").read_text())
    assert set(gains["gains"]) == set(KINDS)
    ref = gains["reference_job"]
    # the default: the lowest RMS contour error on the reference job on the IDENTIFIED plant
    stored = gains["default"]["identified_plant"]
    assert set(stored) == set(KINDS) and len(gains["default"]["coulomb_v"]) == 2
    assert gains["chosen"] == min((k for k in KINDS if not stored[k]["diverged"]), key=lambda k: stored[k]["rms_um"])
    assert (f"default controller: {gains['chosen']} (the lowest RMS contour error (tuning's: to the path within "
            f"+-0.5 s) on {ref} on the identified plant") \
        in " ".join(r.stdout.split())
    assert f"Default controller: **{gains['chosen']}**" in (out / "report" / "closed_loop.md").read_text()
    logs = json.loads((out / "servo" / "pretrain.json").read_text())
    for k in ("nn_axes", "nn_vector"):  # pretrained: integer weights stored, the log beside them
        assert set(gains["gains"][k]) >= {"w1", "w2", "eta_shift", "jacobian", "in_shift"} and logs[k]["kind"] == k
    assert "[servo.x.identified]" in (out / "servo" / "identified.toml").read_text()
    md = (out / "report" / "closed_loop.md").read_text()
    for job in ("servo_step_x25", "servo_step_y20", "servo_step_sequence", "servo_circle"):
        assert f"## {job}.gcode" in md
        for k in KINDS:
            res = json.loads((out / "job" / f"{job}_{k}.json").read_text())
            assert (out / "job" / f"{job}_{k}.png").is_file()
            assert res["controller"] == k and res["contour_um"]["max_um"] >= res["contour_um"]["rms_um"] >= 0
            if job.startswith("servo_step"):  # every step of the seed's tests is measured
                assert len(res["steps"]) == res["reference"]["steps"] >= 1
    for k in ("nn_axes", "nn_vector"):  # a learning controller's clamps, updates and diverged flag in its JSON
        lr = json.loads((out / "job" / f"servo_circle_{k}.json").read_text())["learning"]
        assert lr["updates"] > 0 and lr["diverged"] == (lr["clamps"] > 0.01 * lr["updates"])
    assert "learning" not in json.loads((out / "job" / "servo_circle_pid.json").read_text())
    assert "## Neural controllers against the tuned baselines" in md  # the comparison, its learning curves
    curves = re.findall(r"!\[learning_[^]]*\]\(([^)]+)\)", md)
    assert len(curves) == 2 * 5 and all((out / "report" / c).is_file() for c in curves)
    circle = json.loads((out / "job" / f"servo_circle_{gains['chosen']}.json").read_text())
    assert circle["reversals"]["count"] >= 4  # the circle's quadrants (and the approach's stop)


def test_nnik_job_runs_a_step_closed_loop_in_python(xy_run, tmp_path):
    out, _ = xy_run
    r = nnik("job", out, JOBS / "servo_step_x25.gcode", "--no-chip", "--controller", "pid")
    assert r.returncode == 0, r.stderr
    res = json.loads((out / "job" / "servo_step_x25.json").read_text())
    assert f"contour error: max {res['contour_um']['max_um']:.1f} um, RMS {res['contour_um']['rms_um']:.1f} um" \
        in r.stdout
    (s,) = res["steps"]
    assert s["to_mm"] == [25.0, 0.0] and s["settling_s"] is not None
    assert s["steady_state_um"] < 50  # the PID's integral holds the target within a few counts
    assert "chip: not run (not asked)" in r.stdout


def test_nnik_job_prints_a_learning_controllers_clamps(xy_run):
    out, _ = xy_run
    r = nnik("job", out, JOBS / "servo_step_y20.gcode", "--no-chip", "--controller", "nn_axes")
    assert r.returncode == 0, r.stderr
    lr = json.loads((out / "job" / "servo_step_y20.json").read_text())["learning"]
    assert (f"learning: {lr['updates']} weight updates, {lr['clamps']} clamps ({lr['clamp_pct']:.2f} %): "
            + ("DIVERGED" if lr["diverged"] else "not diverged")) in r.stdout
    r = nnik("job", out, JOBS / "servo_step_y20.gcode", "--no-chip", "--controller", "lqr")
    assert r.returncode == 2 and "invalid choice: 'lqr'" in r.stderr and "nn_vector" in r.stderr


def test_nnik_job_on_the_chip_is_bit_exact(xy_run):
    from nnik.job.servo_loop import chip_missing

    if (why := chip_missing()):
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(why)
        pytest.skip(why)
    out, _ = xy_run
    for k in KINDS:
        r = nnik("job", out, JOBS / "servo_step_sequence.gcode", "--controller", k)
        assert r.returncode == 0, r.stderr
        assert "mismatch 0" in r.stdout.splitlines()
        assert "controller cycles per tick: max" in r.stdout


def test_a_job_outside_the_strokes_is_refused_unless_fitted(xy_run, tmp_path):
    out, _ = xy_run
    job = tmp_path / "big.gcode"
    job.write_text("G21 G90\nG1 X150 Y10 F1200\nG1 X250 Y10\nG1 X150 Y10\n")
    r = nnik("job", out, job, "--no-chip")
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert r.stderr.startswith(f"nnik: error: {job}: the job leaves the workspace") and "--fit" in r.stderr
    assert not (out / "job" / "big.json").exists()
    r = nnik("job", out, job, "--no-chip", "--fit")
    assert r.returncode == 0, r.stderr
    res = json.loads((out / "job" / "big.json").read_text())
    assert res["gcode"]["frame"].startswith("fitted")


def test_an_open_loop_option_on_the_xy_table_is_one_line(xy_run):
    out, _ = xy_run
    r = nnik("job", out, JOBS / "servo_step_x25.gcode", "--shaper", "zv")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--shaper" in r.stderr


def test_nnik_export_writes_the_servo_library_with_the_stored_circle(xy_run, tmp_path):
    """`nnik export OUTDIR --arduino DIR` on the xy_table: the chosen controller's library storing the
    seed's circle (the default job), and --job/--controller choose another; an open-loop model
    directory's export has no --job; an oversized job is one line, nothing written."""
    from nnik.firmware.servo.export import JOB_FLASH_BYTES

    out, _ = xy_run
    chosen = json.loads((out / "servo" / "gains.json").read_text())["chosen"]
    r = nnik("export", out, "--arduino", tmp_path / "lib")
    assert r.returncode == 0, r.stderr
    assert f"example xy_table_servo: {chosen}, job servo_circle.gcode" in r.stdout
    assert (tmp_path / "lib" / "examples" / "xy_table_servo").is_dir()
    config = next((tmp_path / "lib" / "src").glob("nnik_servo_config.h")).read_text()
    assert f"NNIK_CTL_{chosen.upper()} 1" in config
    r = nnik("export", out, "--arduino", tmp_path / "lib2", "--job", JOBS / "servo_step_x25.gcode", "--controller", "pid")
    assert r.returncode == 0 and "example xy_table_servo: pid, job servo_step_x25.gcode" in r.stdout, r.stderr
    long_job = tmp_path / "long.gcode"  # raw steps 10 mm apart, each stored as a 9-byte jump: too many
    long_job.write_text("G21 G90\n" + "".join(f";@step X{10 + 10 * (k % 2)} Y10\n" for k in range(JOB_FLASH_BYTES // 9 + 9)))
    r = nnik("export", out, "--arduino", tmp_path / "lib3", "--job", long_job)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "do not fit" in r.stderr, r.stderr
    assert not (tmp_path / "lib3").exists()


@pytest.mark.parametrize("kind", ("nn_axes", "nn_vector"))
def test_nnik_export_a_neural_controller_builds_with_arduino_mk(xy_run, tmp_path, kind):
    """`nnik export OUTDIR --arduino DIR --controller nn_*`: the library runs the controller from its
    pretrained weights (the run's params in its config header), builds and fits the Uno; the seed's
    125 s circle (about 23.6 kB stored) is too long beside a learning controller: one line, nothing
    written."""
    from nnik.targets.avr import elf_sizes

    out, _ = xy_run
    from nnik.firmware.servo.export import JOB_FLASH_BYTES_LEARNING

    r = nnik("export", out, "--arduino", tmp_path / "circle", "--controller", kind)
    if r.returncode:  # the circle does not fit beside the network
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "do not fit" in r.stderr, r.stderr
        assert f"{JOB_FLASH_BYTES_LEARNING:,} B for the job beside the {kind} controller" in r.stderr
        assert not (tmp_path / "circle").exists()
    r = nnik("export", out, "--arduino", tmp_path / "lib", "--controller", kind, "--job",
             JOBS / "xy_table_reference.gcode")
    assert r.returncode == 0 and f"example xy_table_servo: {kind}, job xy_table_reference.gcode" in r.stdout, r.stderr
    w1 = json.loads((out / "servo" / "gains.json").read_text())["gains"][kind]["w1"]
    config = (tmp_path / "lib" / "src" / "nnik_servo_config.h").read_text()
    assert f"NNIK_CTL_{kind.upper()} 1" in config and f"{w1[0][0][0]}L" in config
    if not Path("/usr/share/arduino/Arduino.mk").is_file() or shutil.which("make") is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("arduino-mk not installed")
        pytest.skip("arduino-mk not installed")
    ex = tmp_path / "lib" / "examples" / "xy_table_servo"
    b = subprocess.run(["make", "-s"], cwd=ex, capture_output=True, text=True, timeout=600)
    assert b.returncode == 0, b.stderr[-800:]
    size = elf_sizes(next((ex / "build-uno").glob("*.elf")), tmp_path)
    assert size["flash"] <= 32 * 1024 - 512 and size["ram"] <= 2048
