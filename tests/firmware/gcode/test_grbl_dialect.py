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
    n_first = 15  # 7.07 mm in 0.5 mm segments
    assert len(plan.ends) == n_first + 2 + 2 + 22  # G92 adds no segment
    ends = np.asarray(plan.ends)
    assert tuple(ends[n_first - 1]) == (5000, 5000)
    assert tuple(ends[n_first + 1]) == (6000, 5000)  # X1 after G92 X0 at X5: machine X6
    # G92 X10 at program X1 (G91 does not apply to G92): program X11 -> machine X-4 + 11 = 7
    assert tuple(ends[n_first + 3]) == (7000, 5000)
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
    plan = interpret(["G1 X1 F600", "G4 P0.5", "G4 P0", "G4 P0.0004", "g4 p0.0005", "G4 P2 X1", "G4 P-1", "G1 X0"], CFG)
    assert plan.replies[5:7] == ["error: line 6: G4 needs P >= 0", "error: line 7: G4 needs P >= 0"]
    seg = steps_of(plan)
    dw = np.flatnonzero(np.asarray(plan.dwell))
    assert dw.tolist() == [2, 3]  # P0 and P0.0004 (0 ms) queue nothing; and seg.ticks[dw].tolist() == [5000, 10]  # 0.5 s; 0.5 ms rounds to 1 ms
    assert not seg.delta[dw].any()
    assert seg.ticks[1] == 500  # 0.5 mm at 600 mm/min


def test_m2_m30_end_the_program_as_grbl():
    plan = interpret(["G91 G0 X1", "M30", "X2", "G2 X2 I1 J0 F600", "M2", "Y1"], CFG)
    assert plan.replies == ["ok"] * 6  # after M30: G1 and G90 (X2 is absolute, not a rapid)
    assert [(m.kind, m.rapid, m.end) for m in plan.moves] == [
        ("line", True, (1000, 0)), ("line", False, (2000, 0)), ("arc", False, (2000, 0)), ("line", False, (2000, 1000))]
