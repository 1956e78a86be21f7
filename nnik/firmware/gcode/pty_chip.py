"""The G-code firmware on a simulated Uno whose UART is a pseudo-terminal, for real senders.

    with PtyChip(fw, workdir) as uno:
        serial.Serial(uno.path, 115200)   # or any sender: cncjs, bCNC, grbl-streamer, ...
    uno.run   # a chip.ChipRun: the firmware's lines, every STEP edge, segment and tool change
    uno.host_lines   # the lines the host sent, as the chip received them

The harness (codegen/harness/arduino/nnik_simavr_pty.c) holds simulated time to wall time
(speed 1.0) so that the sender's timeouts and the firmware's agree; speed 2.0 runs twice as fast.
It cannot run faster than the host allows: on a loaded host the chip's time falls behind the wall
clock, so a wait on the chip is bounded by its simulated time (sim_seconds, wait_sim).
"""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import threading
import time
from pathlib import Path

from nnik.firmware.gcode import chip
from nnik.targets.toolchain import TargetError


class PtyChip:
    def __init__(self, fw: chip.Firmware, workdir: Path, speed: float = 1.0, max_seconds: float = 0.0,
                 link: Path | None = None):
        self.fw, self.workdir = fw, Path(workdir).resolve()
        self.speed, self.max_seconds, self.link = speed, max_seconds, link
        self.events = self.workdir / "pty_events.txt"
        self.path = ""
        self.run: chip.ChipRun | None = None
        self.host_lines: list[str] = []
        self._proc: subprocess.Popen | None = None
        self._cycle = 0  # the simulated clock, as the harness last said it

    def __enter__(self) -> "PtyChip":
        exe = chip.build_pty_harness(self.workdir)
        args = [str(exe), str(Path(self.fw.elf).resolve()), str(self.events), f"{self.max_seconds:g}", f"{self.speed:g}"]
        if self.link:
            args.append(str(self.link))
        self._proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        lines: queue.Queue = queue.Queue()

        def read() -> None:
            for ln in self._proc.stdout:
                if ln.startswith("C "):
                    self._cycle = int(ln.split()[1])
                else:
                    lines.put(ln)

        threading.Thread(target=read, daemon=True).start()
        line, end = "", time.monotonic() + 30
        while not line.startswith("PTY ") and time.monotonic() < end:  # simavr's own chatter first
            try:
                line = lines.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                break
        if not line.startswith("PTY "):
            self._proc.kill()
            raise TargetError(f"simavr pty harness did not start: {line.strip()}")
        self.path = line.split(None, 1)[1].strip()
        return self

    def stop(self) -> chip.ChipRun:
        """End the simulation; parse what it recorded."""
        if self._proc and self._proc.poll() is None:
            self._proc.send_signal(signal.SIGTERM)
            try:
                self._proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        text = self.events.read_text(errors="replace") if self.events.is_file() else ""
        self.run = chip.parse_events(text)
        self.host_lines = [ln.split(" ", 2)[2] if ln.count(" ") >= 2 else ""
                           for ln in text.splitlines() if ln.startswith("H ")]
        return self.run

    def alive(self) -> bool:
        return bool(self._proc) and self._proc.poll() is None

    def cycle_now(self) -> int:
        """The last cycle the harness logged (its events file is buffered: a lower bound)."""
        try:
            with open(self.events, "rb") as f:
                f.seek(max(0, os.path.getsize(self.events) - 200))
                last = f.read().splitlines()[-1].split()
            return int(last[1])
        except (OSError, IndexError, ValueError):
            return 0

    def sim_seconds(self) -> float:
        """The chip's simulated time so far (the harness says it every 10 ms of wall time)."""
        return self._cycle / chip.CLOCK_HZ

    def wait_sim(self, pred, sim_seconds: float, wall_cap: float = 1800.0, step: float = 0.02) -> bool:
        """Poll pred() until true, or until the chip has run sim_seconds of simulated time more
        (however slowly the host runs it), or the harness ended; wall_cap only guards against a
        harness that stopped saying its clock."""
        end_sim = self.sim_seconds() + sim_seconds
        end_wall = time.monotonic() + wall_cap
        while self.sim_seconds() < end_sim and time.monotonic() < end_wall and self.alive():
            if pred():
                return True
            time.sleep(step)
        return bool(pred())

    def __exit__(self, *exc) -> None:
        self.stop()


def wait_until(pred, timeout: float, step: float = 0.02) -> bool:
    """Poll pred() until true or timeout seconds pass."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(step)
    return bool(pred())
