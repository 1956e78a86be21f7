"""One truth for every range (issue 25, part 5): a [motion] the scenario check accepts is one the
firmware runs (its config builds, its header renders, the Python planner runs a job with it, and
a sample compiles with avr-gcc), and a value just outside is refused at the scenario check with
one line naming the key.  The values are drawn at and around each range's edges."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik.errors import NnikError
from nnik.firmware.config import default_machine
from nnik.machine import ranges
from nnik.machine.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
BASE = (ROOT / "datasets" / "galvo_cba2012.toml").read_text()
SAMPLE_HZ = [d for d in range(ranges.MIN_SAMPLE_HZ, ranges.TICK_HZ + 1) if ranges.TICK_HZ % d == 0]
KEYS = ("accel_x_mm_s2", "accel_y_mm_s2", "max_feed_mm_min", "junction_deviation_mm")


def edges(key: str, sample_hz: int) -> tuple[int, int]:
    """The key's range in the firmware's integers (um, um/min, um/s^2)."""
    if key.startswith("accel"):
        return ranges.accel_um_s2_range(sample_hz)
    if key == "max_feed_mm_min":
        return ranges.feed_um_min_range(sample_hz)
    return ranges.JDEV_UM_MIN, ranges.JDEV_UM_MAX


def inside(sample_hz: int) -> dict:
    """Every key at a value well inside its range at this sample rate (the geometric middle)."""
    return {k: round((edges(k, sample_hz)[0] * edges(k, sample_hz)[1]) ** 0.5) / 1000 for k in KEYS}


def scenario(tmp: Path, motion: dict, extra: str = ""):
    motion = {**inside(motion.get("sample_hz", 1000)), **motion}
    body = "\n".join(f"{k} = {v!r}" if isinstance(v, str) else f"{k} = {float(v)!r}" if k != "sample_hz"
                     else f"{k} = {v}" for k, v in motion.items())
    p = tmp / "s.toml"
    p.write_text(BASE + "\n[motion]\n" + body.replace("'", '"') + "\n" + extra)
    return load_scenario(p)


def runs_on_the_firmware(scn) -> None:
    """The firmware config builds, its header renders, and the Python planner runs a short job."""
    from nnik.firmware.arduino import _env
    from nnik.firmware.gcode.motion import interpret
    from nnik.firmware.gcode.sampler import run_ops

    cfg = default_machine(scn)
    header = _env().get_template("gcode_config.h.j2").render(
        name="t", origin=list(cfg.origin_um), seg_um=cfg.seg_um, tick_hz=cfg.tick_hz, feed_um_min=cfg.feed_um_min,
        tool=cfg.tool, shaper=cfg.shaper, tool_defines=cfg.defines())
    assert f"#define NNIK_GC_JDEV_UM {cfg.junction_dev_um}UL" in header
    plan = interpret(["G1 X0.02 Y0.01 F6000", "G1 X0.03 Y0.03", "G0 X0 Y0"], cfg)
    assert all(r == "ok" for r in plan.replies), plan.replies
    s = run_ops(plan.ops, cfg)
    assert s.planned and tuple(s.planned[-1]) == (0, 0)
    return cfg, header


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(sample_hz=st.sampled_from(SAMPLE_HZ), key=st.sampled_from(KEYS), side=st.sampled_from((0, 1)),
       delta=st.one_of(st.sampled_from((-1, 0, 1)), st.floats(-2.0, 2.0)))
def test_every_accepted_value_runs_and_every_value_outside_is_one_line(tmp_path, sample_hz, key, side, delta):
    lo, hi = edges(key, sample_hz)
    value_int = (lo, hi)[side] + delta
    motion = {"sample_hz": sample_hz, key: value_int / 1000}
    inside = lo <= ranges.um(value_int / 1000) <= hi
    if inside:
        runs_on_the_firmware(scenario(tmp_path, motion))
    else:
        with pytest.raises(NnikError) as exc:
            scenario(tmp_path, motion)
        assert f"[motion] {key}: must be in" in str(exc.value) and "\n" not in str(exc.value)


@pytest.mark.parametrize("key", KEYS)
@pytest.mark.parametrize("sample_hz", [100, 1000, 10000])
def test_each_edge_is_accepted_and_one_unit_beyond_is_refused(tmp_path, key, sample_hz):
    lo, hi = edges(key, sample_hz)
    for v in (lo, hi):
        runs_on_the_firmware(scenario(tmp_path, {"sample_hz": sample_hz, key: v / 1000}))
    for v in (lo - 1, hi + 1, 0, -lo):
        with pytest.raises(NnikError, match=rf"\[motion\] {key}: must be in"):
            scenario(tmp_path, {"sample_hz": sample_hz, key: v / 1000})


def test_the_reported_zero_junction_deviation_is_refused(tmp_path):
    with pytest.raises(NnikError, match=r"\[motion\] junction_deviation_mm: must be in \[0.001, 1\] mm"):
        scenario(tmp_path, {"junction_deviation_mm": 0.0})


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(kind=st.sampled_from(("zv", "mzv", "zvd", "ei")), f=st.floats(1.0, 249.0), zeta=st.floats(0.0, 0.9),
       sample_hz=st.sampled_from((500, 1000, 2000)), feed=st.floats(1.0, 30_000.0))
def test_a_shaper_the_scenario_accepts_builds(tmp_path, kind, f, zeta, sample_hz, feed):
    if f >= sample_hz / 4:
        return
    motion = {"sample_hz": sample_hz, "shaper": kind, "max_feed_mm_min": feed}
    try:
        scn = scenario(tmp_path, motion, f"[dynamics]\nf_hz = {f!r}\nzeta = {zeta!r}\n")
    except NnikError as exc:
        assert "[motion]" in str(exc) and "\n" not in str(exc)
        return
    runs_on_the_firmware(scn)


AVR_GCC = shutil.which("avr-gcc")


@pytest.mark.skipif(AVR_GCC is None, reason="avr-gcc not installed")
@pytest.mark.parametrize("sample_hz", [100, 10000])
def test_the_edges_compile_for_the_uno(tmp_path, sample_hz):
    """The planner and the shaper with each edge of the ranges at once, built with avr-gcc -Werror."""
    from nnik.firmware.arduino import ARDUINO

    for side in (0, 1):
        motion = {"sample_hz": sample_hz, **{k: edges(k, sample_hz)[side] / 1000 for k in KEYS}}
        _, header = runs_on_the_firmware(scenario(tmp_path, motion))
        d = tmp_path / f"build{side}"
        d.mkdir()
        (d / "nnik_gcode_config.h").write_text(header)
        (d / "t.h").write_text("/* the IK is not needed by the planner */\n")
        for src in ("nnik_plan.c", "nnik_plan_sample.c", "nnik_shaper.c"):
            r = subprocess.run([AVR_GCC, "-mmcu=atmega328p", "-Os", "-std=c99", "-Wall", "-Wextra", "-Werror",
                                "-I", str(d), "-I", str(ARDUINO / "src"), "-c", str(ARDUINO / "src" / src),
                                "-o", str(d / (src + ".o"))], capture_output=True, text=True)
            assert r.returncode == 0, r.stderr


TOOL_EDGES = {"s_max": ranges.S_MAX_RANGE, "servo_up_deg": ranges.SERVO_DEG_RANGE,
              "servo_down_deg": ranges.SERVO_DEG_RANGE, "m300_down_max": ranges.M300_DOWN_RANGE,
              "pen_z_um": (-ranges.TOOL_Z_UM_MAX, ranges.TOOL_Z_UM_MAX)}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.sampled_from(sorted(TOOL_EDGES)), side=st.sampled_from((0, 1)), delta=st.integers(-2, 2),
       kind=st.sampled_from(("laser", "servo", "pen")))
def test_tool_values_the_scenario_accepts_build_and_others_are_one_line(tmp_path, key, side, delta, kind):
    lo, hi = TOOL_EDGES[key]
    v = (lo, hi)[side] + delta
    p = tmp_path / "s.toml"
    p.write_text(BASE + f'\n[tool]\nkind = "{kind}"\n{key} = {v}\n')
    if lo <= v <= hi:
        runs_on_the_firmware(load_scenario(p))
    else:
        with pytest.raises(NnikError, match=rf"\[tool\] {key}: must be"):
            load_scenario(p)


def test_the_scenarios_tanh_names_are_the_mlp_familys_variants():
    """[export] tanh is checked against ranges.TANH_VARIANTS when the scenario is read (the machine
    layer imports no family): that list must be the MLP family's specs, name for name."""
    from nnik.implementations.mlp.tanh_spec import SPECS
    from nnik.machine import ranges

    assert ranges.TANH_VARIANTS == tuple(s.name for s in SPECS)


@settings(max_examples=200, deadline=None)
@given(move=st.integers(1, (1 << 24) - 1), fr=st.integers(0, (1 << 24) - 1))
def test_the_tools_progress_unit_is_the_finest_whose_increment_fits_a_byte(move, fr):
    """nnik_shaper.h: a sample's progress floor((fr + moved) / 2^PSH), fr < 2^PSH, moved <= move,
    fits uint8, so no window sum of the tool's channel can overflow (255 * 255 < 2^16, and
    2^15 times that < 2^31); a unit one step finer would not fit; never finer than 1/4 um."""
    shift = ranges.progress_shift(move)
    assert shift >= ranges.PROGRESS_SHIFT_MIN
    assert ((fr % (1 << shift)) + move) >> shift <= 255
    assert ((1 << shift) - 1 + move) >> shift <= 255 and 32768 * 255 * 255 < 1 << 31
    if shift > ranges.PROGRESS_SHIFT_MIN:
        assert ((1 << (shift - 1)) - 1 + move) >> (shift - 1) > 255
