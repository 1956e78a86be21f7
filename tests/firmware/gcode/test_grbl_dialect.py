"""grbl's words in the Python model (G92, G28, G4 P, M2/M30, line numbers and checksums, the
modal words that name our only mode) and in nnik_gcode.c on the host: the same answers and
segments."""

from __future__ import annotations

import numpy as np

from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.motion import interpret, plan_steps

CFG = MachineConfig(origin_um=(1000, -2000))


def steps_of(plan, cfg=CFG):
    """Steps with a 10 um-per-step linear 'IK' of the machine position."""
    return plan_steps(plan, cfg, lambda p: (np.asarray(p) // 10, np.zeros(len(p), np.int64)))


def test_g92_shifts_the_program_frame_and_moves_nothing():
    plan = interpret(["G1 X5 Y5 F600", "G92 X0 Y0", "G1 X1", "G91 G92 X10", "G1 X1", "G90 G1 X0 Y0"], CFG)
    assert plan.replies == ["ok"] * 6
    ends = np.asarray(plan.ends)  # one planner block per line; G92 adds none
    assert len(ends) == 4
    assert tuple(ends[0]) == (5000, 5000)
    assert tuple(ends[1]) == (6000, 5000)  # X1 after G92 X0 at X5: machine X6
    # G92 X10 at program X1 (G91 does not apply to G92): program X11 -> machine X-4 + 11 = 7
    assert tuple(ends[2]) == (7000, 5000)
    assert tuple(ends[-1]) == (-4000, 5000)  # program (0, 0) is now machine (-4, 5) less the origin
    seg = steps_of(plan)
    assert np.array_equal(seg.steps[0], np.asarray(CFG.origin_um) // 10)
    assert np.array_equal(seg.steps[-1], (np.asarray(CFG.origin_um) + (-4000, 5000)) // 10)


def test_g28_rapids_to_where_the_motors_started_named_axes_only():
    plan = interpret(["G92 X3 Y4", "G1 X5 Y6", "G28 X6", "G28", "G91 G28 X0 Y1", "M400"], CFG)
    assert plan.replies == ["ok"] * 6
    kinds = [(m.rapid, m.start, m.end) for m in plan.moves]
    assert kinds[1:] == [(True, (2000, 2000), (3000, 2000)), (True, (3000, 2000), (0, 2000)),
                         (True, (0, 2000), (0, 0)), (True, (0, 0), (0, 1000)), (True, (0, 1000), (0, 0))]


def test_g4_dwells_on_the_tick_as_a_segment_without_steps():
    plan = interpret(["G1 X1 F600", "G4 P0.5", "G4 P0", "G4 P0.0004", "g4 p0.0005", "G4", "G4 P-1", "G1 X0"], CFG)
    assert plan.replies[5:7] == ["error:28", "error:4"]  # no P: value word missing; P < 0: negative value
    seg = steps_of(plan)
    assert plan.dwell == [5000, 10]  # P0 and P0.0004 (0 ms) queue nothing; 0.5 ms rounds to 1 ms
    dw = np.flatnonzero(seg.kind == 1)
    assert seg.ticks[dw].tolist() == [5000, 10] and not seg.delta[dw].any()
    # the dwell waits for the motion to come to rest on X1: it follows the first line's last sample
    assert dw[0] == np.flatnonzero(seg.kind == 0)[np.flatnonzero(seg.planned_um[seg.kind == 0, 0] == 1000)[0]] + 1
    assert np.all(seg.ticks[seg.kind == 0] == 10)  # every sample is 1 ms of 10 kHz ticks


def test_m2_m30_end_the_program_as_grbl():
    plan = interpret(["G91 G0 X1", "M30", "X2", "G2 X2 I1 J0 F600", "M2", "Y1"], CFG)
    assert plan.replies == ["ok"] * 6  # after M30: G1 and G90 (X2 is absolute, not a rapid)
    assert [(m.kind, m.rapid, m.end) for m in plan.moves] == [
        ("line", True, (1000, 0)), ("line", False, (2000, 0)), ("arc", False, (2000, 0)), ("line", False, (2000, 1000))]


def test_m4_scales_power_with_the_planned_speed_m3_does_not():
    """M4's power is S's duty x the sample's planned speed / its block's feed (issue 20: the
    planner's speed), so it ramps with the acceleration; M3 holds S's duty; rapids are off;
    M5 and S0 after a cut stop the motion and turn the laser off on a one-tick rest."""
    ik = lambda p: (np.asarray(p) // 10, np.zeros(len(p), np.int64))  # noqa: E731
    cfg = MachineConfig(origin_um=(0, 0))
    lines = ["G1 X10 F3000 M3 S1000", "G1 Y10 M4", "G0 X0", "M4 S500", "G1 Y0 F1500", "S2000", "G1 X5", "M5",
             "G1 X8", "M3", "G1 X9", "S0"]
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik)
    line = np.array([plan.moves[m].line_no for m in seg.move])
    samp = seg.kind == 0
    vn = {1: 50, 2: 50, 5: 25, 7: 25}  # um per sample: F3000 and F1500 at 1 kHz
    for ln, base in ((1, 255), (2, 255), (3, 0), (5, 127), (7, 255), (9, 0), (11, 255)):
        sel = samp & (line == ln) & (seg.speed_q16 > 0)
        d = seg.duty[sel]
        if ln in (2, 5, 7):  # M4
            want = base * np.minimum(seg.speed_q16[sel], vn[ln] * 65536) // (vn[ln] * 65536)
            assert np.array_equal(d, want) and d.min() < base // 4 and d.max() == base, ln
        else:
            assert np.all(d == base), ln
    assert plan.dwell == [1, 1]  # M5 and S0 after a cut: one tick, off
    assert seg.duty[seg.kind == 1].tolist() == [0, 0]


def test_tool_words_at_rest_and_the_pen():
    cfg = MachineConfig(origin_um=(0, 0), tool="servo", pen_z_um=500, servo_up_deg=180, servo_down_deg=0)
    assert (cfg.pen_duty(False), cfg.pen_duty(True)) == (2400 // 64, 544 // 64)
    plan = interpret(["G0 Z1", "G1 X1 Z0.5 F600", "G91 Z0.1", "G90 G4 P0.01", "G1 Y1 Z2", "M3 S9", "G1 Z3"], cfg)
    assert plan.replies == ["ok"] * 7
    assert plan.tool == [8, 37]  # the blocks: X1 down, Y1 up
    assert [op[2] for op in plan.ops if op[0] == "rest"] == [37, 37, 37]  # at rest: up, Z0.6 up, the dwell
    laser = interpret(["G1 Z1 F100 M3 S1000", "G1 X1", "G1 X2 Z-1"], MachineConfig(origin_um=(0, 0)))
    assert laser.replies == ["ok"] * 3 and laser.tool == [255, 255]  # Z is a laser's focus, not its switch
