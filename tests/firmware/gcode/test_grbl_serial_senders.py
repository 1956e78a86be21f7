"""Two grbl senders that other people wrote (PyPI: grbl-streamer, pygrbl-streamer), unmodified,
stream a laser job to the simulated Uno through its pseudo-terminal. Every line is acknowledged,
the senders parse the status reports, and the chip's steps, final position and tool-on path
equal the Python model's (nnik.firmware.gcode.motion) for the lines the chip received."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from nnik.firmware.gcode.chip import CLOCK_HZ
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.gcode.pty_chip import PtyChip
from nnik.firmware.gcode.reader import split_lines
from nnik.firmware.gcode.steps import chip_events, model_events
from tests.firmware.gcode.grbl_pty import grbl_firmware, motor_path, near, tool_on_positions  # noqa: F401

JOBS = Path(__file__).resolve().parents[3] / "datasets" / "jobs"


def check_against_model(entry, uno: PtyChip) -> tuple:
    """The chip's run against the model of the G-code lines it received: (plan, segments)."""
    _, lib, _, ik, _ = entry
    cfg = lib["machine"]
    run = uno.run
    lines = [ln for ln in uno.host_lines if not ln.startswith("$")]  # the senders' own queries apart
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik)
    assert plan.replies == ["ok"] * len(lines)
    answers = [t for _, t in run.replies if t == "ok" or t.startswith("error")]
    assert "error" not in " ".join(answers) and len(answers) == len(uno.host_lines)
    # every step, segment by segment and tick by tick: the chip ran the model's segments
    tick = CLOCK_HZ // cfg.tick_hz
    assert len(run.marks) == len(seg.ticks)
    got, want = chip_events(run.steps, run.marks, tick), model_events(seg)
    assert got.shape == want.shape and np.array_equal(got, want)
    # the final position and the tool-on path, within one step
    path = motor_path(run.steps, seg.steps[0])
    assert np.abs(path[-1] - seg.steps[-1]).max() <= 1
    duty_at = np.zeros(len(run.steps), np.int64)
    if len(run.tool):
        k = np.searchsorted(run.tool[:, 0], run.steps[:, 0], side="right") - 1
        duty_at = np.where(k >= 0, run.tool[np.maximum(k, 0), 1], 0)
    ev = model_events(seg)
    model_path = seg.steps[0] + np.cumsum(
        np.eye(2, dtype=np.int64)[ev[:, 2]] * np.where(ev[:, 3] == 1, 1, -1)[:, None], axis=0)
    model_on = tool_on_positions(model_path, np.asarray(seg.duty)[ev[:, 0]] > 0)
    chip_on = tool_on_positions(path, duty_at > 0)
    assert model_on and near(chip_on, model_on) and near(model_on, chip_on)
    return plan, seg


def stuck(uno: PtyChip, g, events: list) -> str:
    """What a sender that never finished was doing: the chip's time, its last events, the bytes it
    counts in the chip's buffer, the state it last read."""
    quiet = ("on_stateupdate", "on_rx_buffer_percent", "on_progress_percent", "on_read", "on_log", "on_write")
    return (f"at {uno.sim_seconds():.2f} s of chip time: {[e for e, _ in events if e not in quiet][-20:]}, "
            f"counted in flight {g._rx_buffer_fill}, state {g.cmode}")


def settle(uno: PtyChip, g, events: list, hold_s: float = 0.5, tries: int = 10) -> bool:
    """grbl-streamer idle: no query of its poller ($#, $G) due or unanswered, nothing left unread,
    and no new query for hold_s of the chip's time."""
    def queries() -> list[str]:
        return [d[0] for e, d in events if e == "on_write" and d[0].startswith("$")]

    def answered() -> bool:
        gc = sum(1 for e, d in events if e == "on_read" and d[0].startswith("[GC:"))
        return (g.cmode == "Idle" and not g.hash_state_requested and not g.gcode_parser_state_requested
                and queries().count("$G\n") == gc and g._queue.empty())

    for _ in range(tries):
        if not uno.wait_sim(answered, 10):
            return False
        sent, t0 = len(queries()), uno.sim_seconds()
        uno.wait_sim(lambda: uno.sim_seconds() > t0 + hold_s, hold_s + 1)
        if answered() and len(queries()) == sent:
            return True
    return False


def job_lines(path: Path) -> list[str]:
    """A job's lines as a sender sends them (stripped, the blank ones too)."""
    return [ln.decode("latin-1").strip() for ln in split_lines(path.read_bytes())]


def mpos_um(text: str) -> tuple[int, int]:
    x, y = text.split("|MPos:")[1].split("|")[0].split(",")[:2]
    return round(float(x) * 1000), round(float(y) * 1000)


@pytest.mark.xfail(strict=False, reason="grbl-streamer, paced by the wall clock, got 2 errors mid-job with both cores "
                   "busy (fresh-clone CI, 1 of 2 runs): under investigation; chip = model still checked when it passes")
def test_grbl_streamer_streams_a_job(grbl_firmware, tmp_path):
    gs = pytest.importorskip("grbl_streamer")
    job = JOBS / "grbl_cam_laser.gcode"
    events, booted, done = [], threading.Event(), threading.Event()

    def callback(event, *data):
        events.append((event, data))
        if event == "on_boot":
            booted.set()
        elif event == "on_job_completed" and booted.is_set() and any(e == "on_processed_command" for e, _ in events):
            done.set()

    # every wait is bounded in the chip's simulated time, not the wall's: on a loaded host simavr
    # runs the chip slower than real time (and the sender, paced by the wall, meets a slower
    # machine); the job's own bound is its planned time, twice, and 10 s
    _, lib, _, ik, _ = grbl_firmware
    job_s = plan_steps(interpret(job_lines(job), lib["machine"]), lib["machine"], ik).ticks.sum() / lib["machine"].tick_hz
    with PtyChip(grbl_firmware[2], tmp_path) as uno:
        g = gs.GrblStreamer(callback, name="nnik")
        g.cnect(uno.path, 115200)  # opens the terminal, sends Ctrl-X, waits for the banner
        try:
            assert uno.wait_sim(booted.is_set, 15, wall_cap=300)
            g.poll_start()  # '?' every 0.2 s
            assert uno.wait_sim(lambda: g.settings_hash.get("PRB") is not None, 10)  # $# parsed
            # and its $G: grbl-streamer sends it from its polling thread outside its character
            # count, so a job started before that ok would lose count (as with grbl itself)
            assert uno.wait_sim(lambda: any(e == "on_read" and d[0].startswith("[GC:") for e, d in events), 10)
            # and every query its poller sends when the state changes while no job runs ($G on the
            # first report's Idle, too), answered and read, for half a second of the chip's time:
            # an ok read after the job starts would free a job line's bytes in its count
            assert settle(uno, g, events), stuck(uno, g, events)
            g.load_file(str(job))
            g.job_run()
            assert uno.wait_sim(done.is_set, 2 * job_s + 10), stuck(uno, g, events)
            assert uno.wait_sim(lambda: g.cmode == "Idle" and g.streaming_complete, 10)
            t0 = uno.sim_seconds()
            uno.wait_sim(lambda: uno.sim_seconds() > t0 + 0.5, 1)  # a status report or two more
            final = g.cmpos
        finally:
            g.poll_stop()
            g.disconnect()
    plan, seg = check_against_model(grbl_firmware, uno)
    assert not any(e == "on_error" for e, _ in events)
    modes = {d[0] for e, d in events if e == "on_stateupdate"}
    assert {"Run", "Idle"} <= modes  # it parsed the status reports as the job ran
    assert (round(final[0] * 1000), round(final[1] * 1000)) == tuple(int(v) for v in seg.ends_um[-1])


def test_pygrbl_streamer_sends_a_file(grbl_firmware, tmp_path):
    ps = pytest.importorskip("pygrbl_streamer")
    job = JOBS / "lightburn_grbl.gcode"
    with PtyChip(grbl_firmware[2], tmp_path) as uno:
        g = ps.GrblStreamer(uno.path, 115200)
        try:
            g.connect()  # soft reset, banner, a status query
            assert g.send_file(str(job), stop_on_error=True, completion_timeout=120)  # character counting
            status = g.last_status
        finally:
            g.disconnect()
    plan, seg = check_against_model(grbl_firmware, uno)
    assert status["state"] == "Idle"  # it waited for Idle by polling '?' after the last ok
    assert mpos_um(status["raw"]) == tuple(int(v) for v in seg.ends_um[-1])
