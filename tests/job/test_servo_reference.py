"""A closed-loop job's reference (nnik.job.reference): the shipped tests' steps are steps, the
circle has the seed's radius and period, G4 holds, ;@step is a closed-loop directive only, and a
job outside the strokes is refused unless fitted."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from nnik.errors import NnikError
from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
from nnik.firmware.config import default_machine
from nnik.job.parse import JobRequest
from nnik.job.reference import job_reference
from nnik.machine.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
JOBS = ROOT / "datasets" / "jobs"
SCN = load_scenario(ROOT / "datasets" / "xy_table.toml")
UPC = SCN.servo.um_per_count  # 2.5 um


def ref_of(path: Path, **opts):
    return job_reference(JobRequest(path, SCN, opts=JobOptions(**opts)))[1]


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "job.gcode"
    p.write_text(text)
    return p


@pytest.mark.parametrize("job, target", [("servo_step_x25.gcode", (10000, 0)), ("servo_step_y20.gcode", (0, 8000))])
def test_a_shipped_step_is_one_jump_of_the_reference(job, target):
    r = ref_of(JOBS / job)
    k = r.step_ticks[0]
    assert len(r.step_ticks) == 1
    assert (r.counts[:k] == 0).all()  # at rest at the homing corner
    assert (r.counts[k:] == target).all()  # 25 mm = 10,000 counts (20 mm = 8,000) at once, then held
    assert (len(r.counts) - k) * r.tick_s == pytest.approx(3.0, abs=0.01)  # G4 P3 holds


def test_the_step_sequence_steps_x_then_y_then_both_back():
    r = ref_of(JOBS / "servo_step_sequence.gcode")
    held = [tuple(r.counts[k]) for k in r.step_ticks]
    assert held == [(10000, 0), (10000, 8000), (0, 0)]
    changes = np.flatnonzero(np.any(np.diff(r.counts, axis=0) != 0, axis=1)) + 1
    assert changes.tolist() == list(r.step_ticks)  # nothing moves but at the steps


def test_the_circle_has_the_seeds_radius_mean_and_period():
    r = ref_of(JOBS / "servo_circle.gcode")
    um = r.counts * UPC
    on = np.flatnonzero(np.any(np.diff(r.counts, axis=0) != 0, axis=1))
    # the circle: after the approach and the 1 s hold, until the last hold
    hold = np.flatnonzero(np.all(np.diff(r.counts, axis=0) == 0, axis=1))
    start = hold[np.searchsorted(hold, on[0])] + 1  # the first hold after the approach ends
    circle_ticks = np.arange(start, on[-1] + 2)
    c = um[circle_ticks]
    radius = np.hypot(c[:, 0] - 20000, c[:, 1] - 20000)
    # within 2 counts: half a count per axis, the planner's um and the 0.5 mm chords' 1.6 um sagitta
    assert np.abs(radius - 20000).max() <= 2 * UPC
    assert c[:, 0].min() == 0 and c[:, 0].max() == pytest.approx(40000, abs=UPC)  # mean 20, amplitude 20
    seconds = len(circle_ticks) * r.tick_s
    assert seconds == pytest.approx(125.0, rel=0.01)
    ang = np.unwrap(np.arctan2(c[:, 0] - 20000, c[:, 1] - 20000))  # x = sin, y = cos: clockwise from (20, 40)
    assert ang[-1] - ang[0] == pytest.approx(2 * np.pi, abs=0.01)
    t = np.arange(len(c)) * r.tick_s
    rate = np.polyfit(t[len(t) // 10:-len(t) // 10], ang[len(t) // 10:-len(t) // 10], 1)[0]
    assert 2 * np.pi / rate == pytest.approx(125.0, rel=0.005)


def test_every_shipped_closed_loop_job_lies_inside_the_strokes():
    for job in sorted(JOBS.glob("servo_*.gcode")) + sorted(JOBS.glob("xy_table_*.gcode")):
        um = ref_of(job).counts * UPC
        assert um.min() >= 0 and um[:, 0].max() <= 200000 and um[:, 1].max() <= 150000, job.name


def test_a_dwell_holds_the_reference_for_its_whole_ticks(tmp_path):
    r = ref_of(write(tmp_path, "G1 X10 F600\nG4 P0.503\nG1 X20\n"))
    still = np.all(np.diff(r.counts, axis=0) == 0, axis=1)
    run = max(len(s) for s in "".join("1" if v else "0" for v in still).split("0"))
    assert run >= 101  # 0.503 s = 100.6 ticks, rounded up


@settings(max_examples=25, deadline=None)
@given(x=st.integers(0, 195), y=st.integers(0, 145), rel=st.booleans())
def test_a_step_reads_its_target_as_g0_would(tmp_path_factory, x, y, rel):
    p = tmp_path_factory.mktemp("step") / "s.gcode"
    p.write_text(f"G21 G90\nG1 X5 Y5 F600\n{'G91' if rel else 'G90'}\n;@step X{x} Y{y}\nG4 P0.1\n")
    r = ref_of(p)
    want = ((x + 5) * 400, (y + 5) * 400) if rel else (x * 400, y * 400)
    assert tuple(r.counts[-1]) == want
    if want == (2000, 2000):  # already there: no step
        assert r.step_ticks == ()
    else:
        k = r.step_ticks[0]
        assert len(r.step_ticks) == 1 and tuple(r.counts[k - 1]) == (2000, 2000) and tuple(r.counts[k]) == want


def test_a_job_outside_the_strokes_is_refused_and_fits_with_fit(tmp_path):
    p = write(tmp_path, "G21 G90\nG1 X250 Y10 F600\nG1 X-10 Y10\n")
    with pytest.raises(NnikError, match="leaves the workspace.*--fit"):
        ref_of(p)
    um = ref_of(p, fit=True).counts * UPC
    assert um.min() >= 0 and um[:, 0].max() <= 200000


def test_a_step_outside_the_strokes_is_refused(tmp_path):
    with pytest.raises(NnikError, match="leaves the workspace"):
        ref_of(write(tmp_path, ";@step X-1\nG4 P1\n"))


@pytest.mark.parametrize("line", [";@step", ";@step Z3", ";@step X1 X2", ";@step X1 F100", ";@step Xfoo"])
def test_a_malformed_step_is_one_line_naming_the_file_and_line(tmp_path, line):
    p = write(tmp_path, f"G4 P0.1\n{line}\n")
    with pytest.raises(NnikError, match=r"job\.gcode:2: ;@step takes X and/or Y"):
        ref_of(p)


def test_an_open_loop_machine_refuses_a_step(tmp_path):
    p = write(tmp_path, "G1 X1 F100\n  ; @STEP X25\n")
    with pytest.raises(NnikError, match=r"job\.gcode:2: ;@step .* closed-loop job"):
        prepare(read_job(p), default_machine(load_scenario(ROOT / "datasets" / "galvo_cba2012.toml")), JobOptions(),
                str(p))
