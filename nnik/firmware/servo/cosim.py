"""The closed-loop co-simulation: the servo firmware on the simulated Uno (nnik_simavr_servo, in
lockstep over a pipe) drives the Python plant, and the controller's integer Python model, fed the
same reference and the counts the chip latched, predicts every duty (chip = model, tick by tick)
and, for a learning controller, its weights: the chip's weight checksum (nnik_servo_sum, the sum of
every int32 master word modulo 2^16 after the tick) against the model's checksum() (0 for the
fixed-gain controllers, whose chip reports 0). A tick mismatches when a duty or the checksum differs.

Per tick k: the harness gets ref[k] and the plant's substep counts of the tick before (edges on
PC0..PC3, spread after the last tick's computation and away from tick k's latch); the chip latches
its counts, computes and answers its duty, which the plant then holds for tick k. The plant is
driven by the chip's duty (the machine's behaviour); the model's duty is only compared.

CPU load: the co-simulation build's main loop sleeps, so the cycles the chip is awake in a tick
(simavr's count; the interrupt entries and the main loop's return to sleep included) are the
interrupts' work: load % = awake cycles / tick cycles * 100.
"""

from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.firmware.servo.build import ServoFirmware, build_harness
from nnik.targets.toolchain import TargetError, first_error_line

ANSWER = 13  # int32 per tick from the harness


@dataclass
class ChipTrace:
    chip_duty: np.ndarray  # (N, 2) the chip's duty per tick
    model_duty: np.ndarray  # (N, 2) the Python model's
    counts: np.ndarray  # (N, 2) the counts the chip latched at each tick
    plant_counts: np.ndarray  # (N, 2) the plant's counts at each tick
    ctl_cycles: np.ndarray  # (N,) the busy pin's cycles (the controller and the outputs), nested encoder ISRs out
    tick_isr_cycles: np.ndarray  # (N,) the tick interrupt's cycles, nested encoder ISRs out
    enc_cycles: np.ndarray  # (N,) the encoder interrupts' cycles in the tick before
    enc_isrs: np.ndarray  # (N,) their number
    awake_cycles: np.ndarray  # (N,) the cycles the chip was awake in the tick before
    period_cycles: int
    table_um: np.ndarray | None = None  # (N, 2) the carriage after each tick, if the plant gives it
    chip_sum: np.ndarray | None = None  # (N,) the chip's weight checksum after each tick (0: no weights)
    model_sum: np.ndarray | None = None  # (N,) the model's checksum() after each tick

    def __post_init__(self):
        n = len(self.chip_duty)
        self.chip_sum = np.zeros(n, np.int64) if self.chip_sum is None else np.asarray(self.chip_sum, np.int64)
        self.model_sum = np.zeros(n, np.int64) if self.model_sum is None else np.asarray(self.model_sum, np.int64)

    @property
    def mismatch_ticks(self) -> np.ndarray:
        """The ticks where a duty or the weight checksum differs."""
        return np.flatnonzero((self.chip_duty != self.model_duty).any(axis=1) | (self.chip_sum != self.model_sum))

    @property
    def mismatches(self) -> int:
        return int(self.mismatch_ticks.size)

    @property
    def lost_counts(self) -> int:
        """Ticks where the chip's latched count differs from the plant's (an edge lost)."""
        return int((self.counts != self.plant_counts).any(axis=1).sum())

    @property
    def cycles_max(self) -> int:
        return int(self.ctl_cycles.max()) if len(self.ctl_cycles) else 0

    @property
    def load_pct_max(self) -> float:
        """The busiest tick's awake cycles (tick + encoder interrupts) as % of the tick."""
        return float(self.awake_cycles.max()) / self.period_cycles * 100 if len(self.awake_cycles) else 0.0


class ChipSession:
    """The harness process for one run: tick(ref, substep_counts) -> the answer's 13 ints."""

    def __init__(self, fw: ServoFirmware, substeps: int, start_counts, workdir: Path, uart_log: Path | None = None):
        exe = build_harness(Path(workdir) / "harness")
        s = fw.symbols
        self.substeps = substeps
        self._err = open(Path(workdir) / "servo_harness.stderr", "w+")
        cmd = [str(exe), str(fw.elf), str(fw.period_cycles), str(substeps), str(s["nnik_servo_feed"]),
               str(s["nnik_servo_count"]), str(s["nnik_servo_pos"]), *(str(int(c)) for c in start_counts),
               str(s.get("nnik_servo_sum", 0))]
        try:
            env = None if uart_log is None else dict(os.environ, NNIK_SERVO_UART=str(uart_log))
            self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._err, env=env)
        except OSError as exc:
            raise TargetError(f"servo co-simulation: cannot run {exe}: {exc}") from None

    def tick(self, ref, rows) -> np.ndarray:
        req = np.empty(2 + 2 * self.substeps, dtype="<i4")
        req[:2] = ref
        req[2:] = np.asarray(rows, dtype=np.int64).reshape(-1)
        try:
            self.proc.stdin.write(req.tobytes())
            self.proc.stdin.flush()
            data = self.proc.stdout.read(4 * ANSWER)
        except BrokenPipeError:
            data = b""
        if len(data) != 4 * ANSWER:
            self.close()
            self._err.seek(0)
            raise TargetError(f"servo co-simulation failed: {first_error_line(self._err.read())}")
        return np.frombuffer(data, dtype="<i4").astype(np.int64)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.stdin.close()
            self.proc.wait()
        self._err.close()


def run(fw: ServoFirmware, cfg, controller, ref_counts, workdir: Path | None = None, plant=None,
        start_counts=(0, 0), model_duty=None, uart_log: Path | None = None, model_sum=None) -> ChipTrace:
    """Run ref_counts ((N, 2) int, counts) closed loop: the chip (fw) drives `plant` (default
    nnik.dynamics.servo.plant.Plant(cfg, start_counts)); `controller` (the integer Python model,
    reset first) predicts each duty. model_duty(k, duty) may replace the model's duty (a test's
    deliberately wrong model), model_sum(k, checksum) the model's checksum. workdir: where the harness is built and logs (default: beside the
    firmware's ELF). uart_log: a file that receives every byte the chip sends on its UART."""
    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    if len(ref) == 0:
        raise NnikError("servo co-simulation: no ticks in the reference")
    if np.abs(ref).max() >= 2**31:
        raise NnikError("servo co-simulation: a reference beyond int32 counts")
    if plant is None:
        from nnik.dynamics.servo.plant import Plant
        plant = Plant(cfg, start_counts)
    start = tuple(int(c) for c in plant.counts)
    workdir = Path(workdir) if workdir is not None else Path(fw.elf).parent / "cosim"
    workdir.mkdir(parents=True, exist_ok=True)
    n = len(ref)
    out = {k: np.zeros((n, 2), np.int64) for k in ("chip", "model", "counts", "plant")}
    scal = np.zeros((n, 5), np.int64)
    sums = np.zeros((n, 2), np.int64)  # the chip's checksum, the model's
    table = np.zeros((n, 2))
    controller.reset()
    chip = ChipSession(fw, cfg.substeps, start, Path(workdir), uart_log)
    rows = np.tile(np.asarray(start, dtype=np.int64), (cfg.substeps, 1))
    try:
        for k in range(n):
            ans = chip.tick(ref[k], rows)
            duty = (int(ans[0]), int(ans[1]))
            pos = (int(ans[2]), int(ans[3]))
            out["plant"][k] = plant.counts
            out["counts"][k] = pos
            m = controller.tick((int(ref[k, 0]), int(ref[k, 1])), pos)
            out["model"][k] = m if model_duty is None else model_duty(k, m)
            out["chip"][k] = duty
            s = int(controller.checksum())
            sums[k] = ans[12], s if model_sum is None else model_sum(k, s)
            scal[k] = ans[4], ans[5], ans[6], ans[7], ans[8]
            rows = plant.step(duty)
            table[k] = plant.table_um
    finally:
        chip.close()
    return ChipTrace(out["chip"], out["model"], out["counts"], out["plant"], scal[:, 0], scal[:, 1], scal[:, 2],
                     scal[:, 3], scal[:, 4], fw.period_cycles, table, sums[:, 0], sums[:, 1])
