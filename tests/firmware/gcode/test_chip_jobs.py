"""Jobs however they end, and R-form arcs, on the simulated Uno: every segment runs (the harness
waits until the machine is idle, not for the answer to the last line), every step equals the
Python model's, and the run ends when the last tick is over."""

from __future__ import annotations

import pytest

from tests.firmware.gcode.conftest import run_both

MACHINES = ["galvo_cba2012", "corexy_nonlinear"]

# a five-pointed star, I/J and R arcs (short and long, both directions), no M400 at the end
STAR_ARCS = ["G21 G90 F6000", "G0 X0 Y5", "G1 X2.939 Y-4.045", "X-4.755 Y1.545", "X4.755 Y1.545",
             "X-2.939 Y-4.045", "X0 Y5", "G2 X5 Y0 I0 J-5", "G3 X0 Y-5 R5", "G2 X-5 Y0 R-5",
             "G91 G3 X5 Y5 R5", "G90 G2 X0 Y-3 R-4.5"]


@pytest.mark.parametrize("scenario", MACHINES)
def test_one_line_without_m400_runs_all_its_segments(firmware, scenario):
    plan, seg, res = run_both(firmware[scenario], ["G1 X2 F3000"])
    assert len(plan.ends) == 1 and len(res.marks) == len(seg.ticks) > 20  # one block, a segment per 1 ms sample
    assert tuple(seg.planned_um[-1]) == (2000, 0) and seg.speed_q16[-1] > 0  # it ends on X2 (at rest after it)


@pytest.mark.parametrize("scenario", MACHINES)
def test_blocks_past_65_mm_match(firmware, scenario):
    """The sample's point takes u s / 2^30 from 8 byte products while s, the whole um along the block,
    is below 2^16, and libgcc's 64-bit product from 65.536 mm on (nnik_plan.c, mul_q30): both ways
    give the model's steps on the chip."""
    lines = ["G21 G90", "G0 X-40 Y-30", "G1 X40 Y35 F3000", "G1 X-38 Y30", "M400"]
    plan, seg, _ = run_both(firmware[scenario], lines)
    assert plan.replies == ["ok"] * len(lines)
    assert tuple(seg.planned_um[-1]) == (-38000, 30000)  # two blocks of 103 and 78 mm, sampled to their ends


@pytest.mark.parametrize("scenario", MACHINES)
@pytest.mark.parametrize("ending", [[], ["M2"], ["M30"], ["M400"]])
def test_star_and_arcs_match_however_the_job_ends(firmware, scenario, ending):
    plan, seg, res = run_both(firmware[scenario], STAR_ARCS + ending)
    assert plan.replies == ["ok"] * len(STAR_ARCS + ending)
    arcs = [m for m in plan.moves if m.kind == "arc"]
    assert len(arcs) == 5 and len(seg.ticks) > 150


def test_bad_r_arcs_get_the_same_error_on_the_chip(firmware):
    lines = ["G1 X1 F3000", "G2 X10 R2", "G2 X1 Y2 I1 R1", "G1 X2 R1", "G3 X1 R0", "G2 R3", "G3 X3 R-1",
             "G2 X2 Y1 R-1"]
    plan, _, _ = run_both(firmware["corexy_nonlinear"], lines)
    # grbl's numbers: invalid target (chord > 2|R|), unused words (I beside R; R on G1), invalid target
    # (R0), an arc without its end (32)
    assert plan.replies[1:6] == ["error:33", "error:36", "error:36", "error:33", "error:32"]
    assert plan.replies[6:] == ["ok", "ok"]


# the grbl-style job without the tool: N numbers, a checksum, the modal header, G92, G28,
# a dwell, lower case, I/J arcs and M30
GRBL = ["N1 G17 G21 G90 G40 G49 G80 G94*24", "N2 G92 X0 Y0", "N3 g0 x5 y5", "N4 G1 X8 F3000", "N5 G4 P0.05",
        "N6 G2 X5 Y8 I-3 J0", "N7 G92 X0 Y0", "N8 G91 G1 X-2 Y-2", "N9 G28", "N10 G4 P0.0123", "N11 G18",
        "N12 M30"]


@pytest.mark.parametrize("scenario", MACHINES)
def test_grbl_words_on_the_chip(firmware, scenario):
    plan, seg, res = run_both(firmware[scenario], GRBL)
    assert plan.replies == ["ok"] * 12  # G18: a plane (the Uno build carries planes)
    dwell = [t for t in plan.dwell if t]
    assert dwell == [500, 120]  # ticks at 10 kHz (P in whole ms), each a segment on the chip too
    assert plan.ends[-1] == (0, 0)  # G28: back where the motors started, after two G92s


# the tool on D11: M3 constant, M4 scaled, off in rapids, M5 at rest, S over $30 clamped
LASER = ["G21 G90 F3000", "M3 S500", "G0 X1 Y1", "G1 X3", "S1000", "G1 Y3", "M4 S800", "G1 X1 F1500", "G4 P0.01",
         "G2 X1 Y1 I0 J-1", "M5", "G0 X0 Y0", "M3 S2000", "G1 X1", "M30"]


def test_laser_tool_changes_on_the_chip(firmware):
    plan, seg, res = run_both(firmware["corexy_nonlinear"], LASER)
    assert plan.replies == ["ok"] * len(LASER)
    assert {0, 127, 255, 204} <= set(seg.duty.tolist())  # S500, S1000, M4 S800 at full speed
    assert len(res.tool) >= 7 and res.tool[-1, 1] == 0  # M30 turned it off


PEN = ["G21 G90 F3000", "G0 Z5", "G0 X2 Y2", "G1 Z0", "G4 P0.02", "G1 X4", "G0 Z1", "G0 X0", "G1 X-1 Y-1 Z-1",
       "G91 G0 Z2", "G90 G1 Z0.2", "M5", "G0 Z1", "M2"]


def test_servo_pen_changes_on_the_chip(pen_firmware):
    plan, seg, res = run_both(pen_firmware, PEN)
    cfg = pen_firmware[1]["machine"]
    assert plan.replies == ["ok"] * len(PEN)
    up, down = cfg.pen_duty(False), cfg.pen_duty(True)
    assert res.tool[:, 1].tolist() == [up, down, up, down, up, down, up]
