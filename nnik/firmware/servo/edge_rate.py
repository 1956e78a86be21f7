"""The highest encoder edge rate two axes sustain on the simulated Uno: the harness's sweep mode
(nnik_simavr_servo -r) moves both axes forward at a steady rate (Y's edges half an interval after
X's), through the ticks' computations (the tick interrupt re-enables interrupts after its latch, so
the encoder interrupt preempts it), then stops and compares the chip's counts with the edges sent.
Sustained: no count lost and every tick's computation ended before the next tick was due (the
encoder interrupt has the higher priority: past the CPU's capacity it starves the tick, not the
count). The search bisects the edge interval in whole cycles."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from nnik.firmware.servo.build import CLOCK_HZ, ServoFirmware, build_harness
from nnik.targets.toolchain import TargetError, run


@dataclass(frozen=True)
class EdgeRun:
    rate: float  # edges/s per axis
    edges: int  # per axis
    counted: tuple[int, int]
    awake_max: int  # the busiest tick period's awake cycles
    late_max: int  # the latest a tick's computation ended after its due time, cycles
    period: int

    @property
    def lost(self) -> int:
        return max(abs(self.edges - c) for c in self.counted)

    @property
    def sustained(self) -> bool:
        return self.lost == 0 and self.late_max < self.period


def edge_run(fw: ServoFirmware, gap_cycles: int, ticks: int, workdir: Path) -> EdgeRun:
    """Both axes at one edge every gap_cycles for `ticks` ticks."""
    exe = build_harness(Path(workdir) / "harness")
    rate = CLOCK_HZ / gap_cycles
    res = run([exe, "-r", f"{rate!r}", str(ticks), fw.elf, str(fw.period_cycles), str(fw.symbols["nnik_servo_count"])],
              "servo edge-rate run", cwd=Path(workdir))
    parts = res.stdout.split()
    if len(parts) != 9 or parts[0] != "edges":
        raise TargetError(f"servo edge-rate run: unexpected answer {res.stdout.strip()[:80]!r}")
    return EdgeRun(rate, int(parts[1]), (int(parts[3]), int(parts[4])), int(parts[6]), int(parts[8]),
                   fw.period_cycles)


def max_edge_rate(fw: ServoFirmware, workdir: Path, ticks: int = 20, gap_lo: int = 8, gap_hi: int = 16000) -> EdgeRun:
    """The fastest steady rate (the smallest edge interval, cycles) sustained over `ticks` ticks:
    bisection between gap_lo (not sustained) and gap_hi (must be)."""
    Path(workdir).mkdir(parents=True, exist_ok=True)
    best = edge_run(fw, gap_hi, ticks, workdir)
    if not best.sustained:
        raise TargetError(f"the chip does not sustain even {best.rate:.0f} edges/s")
    if edge_run(fw, gap_lo, ticks, workdir).sustained:
        raise TargetError(f"the chip sustains even {CLOCK_HZ / gap_lo:.0f} edges/s: widen the search")
    lo, hi = gap_lo, gap_hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        r = edge_run(fw, mid, ticks, workdir)
        if r.sustained:
            hi, best = mid, r
        else:
            lo = mid
    return best
