"""Helpers for the grbl serial tests: the firmware built once, a port that reads grbl's lines,
and the chip's path against the Python model's."""

from __future__ import annotations

import queue
import re
import threading
import time

import numpy as np
import pytest

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.firmware.gcode import chip
from nnik.firmware.ik_oracle import ik_oracle
from tests.firmware.gcode.conftest import require_chip

BANNER = "Grbl 1.1h ['$' for help]"
STATUS = re.compile(r"^<(Idle|Run|Hold:[01]|Alarm|Check)\|MPos:(-?\d+\.\d{3}),(-?\d+\.\d{3}),(-?\d+\.\d{3})"
                    r"\|Bf:(\d+),(\d+)\|FS:(\d+),(\d+)(\|WCO:-?\d+\.\d{3},-?\d+\.\d{3},-?\d+\.\d{3}\|Ov:100,100,100)?>$")


@pytest.fixture(scope="session")
def grbl_firmware(galvo_run, tmp_path_factory):
    """galvo_cba2012's G-code firmware (the grbl front end): (model dir, library info, firmware,
    IK oracle, work dir)."""
    require_chip()
    pytest.importorskip("serial")
    pipeline.export(galvo_run)
    work = tmp_path_factory.mktemp("grbl")
    lib = export_arduino(galvo_run, work / "lib")
    fw = chip.build_sketch(work / "lib", "galvo_cba2012_gcode", work / "build", lib["machine"].defines())
    return galvo_run, lib, fw, ik_oracle(galvo_run), work


class GrblPort:
    """A serial port on the chip's terminal that splits what comes back into lines (status
    reports apart)."""

    def __init__(self, path: str):
        import serial

        self.s = serial.Serial(path, 115200, timeout=0.05)
        self.lines: queue.Queue = queue.Queue()
        self.status_lines: queue.Queue = queue.Queue()
        self._stop = False
        self._t = threading.Thread(target=self._read, daemon=True)
        self._t.start()

    def _read(self):
        buf = b""
        while not self._stop:
            try:
                buf += self.s.read(256)
            except Exception:
                return
            while b"\n" in buf:
                raw, buf = buf.split(b"\n", 1)
                text = raw.decode("latin-1").rstrip("\r")
                (self.status_lines if text.startswith("<") else self.lines).put(text)

    def close(self):
        self._stop = True
        self._t.join(2)
        self.s.close()

    def write(self, data: bytes | str):
        self.s.write(data.encode() if isinstance(data, str) else data)

    def next_line(self, timeout: float = 5.0) -> str:
        return self.lines.get(timeout=timeout)

    def until(self, pred, timeout: float = 5.0) -> list[str]:
        """Lines up to and including the first that pred accepts."""
        out, end = [], time.monotonic() + timeout
        while True:
            line = self.lines.get(timeout=max(0.01, end - time.monotonic()))
            out.append(line)
            if pred(line):
                return out

    def banner(self, timeout: float = 10.0) -> list[str]:
        return self.until(lambda ln: ln == BANNER, timeout)

    def cmd(self, line: str, timeout: float = 10.0) -> list[str]:
        """Send a line, return what came back up to its ok / error:N."""
        self.write(line + "\n")
        return self.until(lambda ln: ln == "ok" or ln.startswith("error:"), timeout)

    def status(self, timeout: float = 5.0) -> re.Match:
        while not self.status_lines.empty():
            self.status_lines.get_nowait()
        self.write(b"?")
        text = self.status_lines.get(timeout=timeout)
        m = STATUS.match(text)
        assert m, text
        return m

    def wait_state(self, state: str, timeout: float = 20.0) -> re.Match:
        end = time.monotonic() + timeout
        while True:
            m = self.status()
            if m.group(1) == state or time.monotonic() > end:
                return m
            time.sleep(0.05)


def motor_path(steps: np.ndarray, start) -> np.ndarray:
    """Motor counts after each recorded step (cycle, motor, dir), from start."""
    inc = np.zeros((len(steps), 2), np.int64)
    inc[np.arange(len(steps)), steps[:, 1]] = np.where(steps[:, 2] == 1, 1, -1)
    return np.asarray(start, np.int64) + np.cumsum(inc, axis=0)


def tool_on_positions(path: np.ndarray, on: np.ndarray) -> set:
    return {tuple(p) for p in path[on].tolist()}


def near(a: set, b: set, tol: int = 1) -> bool:
    """Every point of a within tol counts (per motor) of a point of b."""
    if not a:
        return True
    bb = np.asarray(sorted(b), np.int64).reshape(-1, 2)
    if not len(bb):
        return False
    return all(np.abs(bb - np.asarray(p)).max(axis=1).min() <= tol for p in a)
