"""Run the simavr job harness (codegen/harness/arduino/nnik_simavr_job.c) and read what it recorded.

The harness writes its pin events (steps, segment marks, the busy pin, the tool's PWM) as binary
records to a file, read at once with numpy, and prints the firmware's lines (R), the drain's
answer (D) and the end (E) on stdout as it goes: a long job's progress is the answers counted
there, with an ETA on a terminal (nnik.progress).
"""

from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass
import threading
from pathlib import Path
from typing import Callable

import numpy as np

from nnik.targets.toolchain import TargetError, first_error_line


@dataclass
class ChipRun:
    """What the simulated chip did: replies, step events, segment starts, busy windows."""

    replies: list[tuple[int, str]]  # (cycle, text), the banner included
    steps: np.ndarray  # (K, 3) int64: cycle, motor, dir (1: positive)
    marks: np.ndarray  # (S,) cycles at which segments started
    busy: np.ndarray  # (B, 2) cycles: rise, fall of the busy pin
    end_cycle: int
    state: str
    idle_cycle: int = 0  # the motion pin's last fall before the drain answer: the true end; 0: no motion
    tool: np.ndarray | None = None  # (T, 2) int64: cycle, duty of every change of the tool's PWM (D11)
    stack_bytes: int = 0  # the deepest stack seen: RAMEND less the lowest stack pointer

COMMENT_OR_BLANK = re.compile(r"\s|\(.*?\)|;.*")  # grbl's stream.py strips \s and (...); grbl-streamer ';...' too


def sender_line(raw: str) -> str:
    """The line as a character-counting sender sends it (grbl's stream.py, grbl-streamer, UGS,
    cncjs): its whitespace and comments out, so that they take no room in the firmware's receive
    buffer (a comment-only or blank line becomes an empty one, still answered) - where the
    firmware's reader (nnik.firmware.gcode.reader, its model) reads the same; where it would not
    (a checksum covers the bytes), the line as it is."""
    from nnik.firmware.gcode.reader import read_line, sendable

    clean = COMMENT_OR_BLANK.sub("", raw)
    if clean == raw:
        return raw
    try:  # the harness sends latin-1 (the job's bytes as read)
        same = read_line(sendable(clean.encode("latin-1"))) == read_line(sendable(raw.encode("latin-1")))
    except UnicodeEncodeError:
        return raw
    return clean if same else raw


EVENT = np.dtype([("cycle", "<u8"), ("tag", "<u4"), ("value", "<i4")])  # struct event in the harness


def is_answer(text: str) -> bool:
    """A line that answers a line sent: "ok", or an error (the old "error: ..." or grbl's "error:N")."""
    return text.startswith(("ok", "error:"))


def read_events(path: Path):
    """(steps (K, 3): cycle, motor, dir; marks (S,); busy (B, 2): rise, fall; tool (T, 2): cycle,
    duty), int64, in the order the harness recorded them."""
    ev = np.fromfile(path, dtype=EVENT)
    tag, cyc, val = ev["tag"], ev["cycle"].astype(np.int64), ev["value"].astype(np.int64)
    s = tag == ord("S")
    steps = np.stack([cyc[s], val[s] & 1, val[s] >> 1], 1).reshape(-1, 3)
    marks = cyc[tag == ord("M")]
    b = tag == ord("B")
    rises, falls = cyc[b][val[b] == 1], cyc[b][val[b] == 0]
    n = min(len(rises), len(falls))
    busy = np.stack([rises[:n], falls[:n]], 1).reshape(-1, 2)
    t = tag == ord("T")
    tool = np.stack([cyc[t], val[t]], 1).reshape(-1, 2)
    return steps, marks, busy, tool


def run_harness(exe: Path, elf: Path, lines: list[str], workdir: Path, max_seconds: float, mcu: str,
                progress: Callable[[int, int], None] | None = None, rx_bytes: int = 0):
    """Send lines to the firmware (then M400) on simavr; progress(answers so far, its cycle) after
    each answer. rx_bytes: character counting within the firmware's receive buffer of that many
    bytes (chip.rx_buffer_bytes()); 0: send-response, one line in flight.
    Returns chip.ChipRun; a harness that fails, or runs past its wall-clock bound, -> TargetError."""
    job = workdir / "job_lines.txt"
    job.write_bytes("".join(f"{ln}\n" for ln in lines).encode("latin-1"))
    events = workdir / "job_events.bin"
    events.unlink(missing_ok=True)
    err = workdir / "harness.stderr"
    counting = ["-c", str(rx_bytes)] if rx_bytes else []
    cmd = [str(exe), "-m", mcu, "-e", str(events), *counting, str(elf), str(job), f"{max_seconds:g}"]
    timeout = 120 + 60 * max_seconds
    replies, idle_cycle, end_cycle, state, answers = [], 0, 0, "missing", 0
    sp_low = ramend = 0
    with open(err, "w") as ferr:
        try:
            proc = subprocess.Popen(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=ferr, stdin=subprocess.DEVNULL,
                                    text=True, errors="replace", bufsize=1)
        except OSError as exc:
            raise TargetError(f"simavr job: cannot run {exe}: {exc}") from None
        killed = threading.Event()

        def kill():
            killed.set()
            proc.kill()

        timer = threading.Timer(timeout, kill)
        timer.start()
        try:
            for line in proc.stdout:
                tag, _, rest = line.rstrip("\n").partition(" ")
                if tag == "R":
                    cyc, _, msg = rest.partition(" ")
                    replies.append((int(cyc), msg))
                    if progress is not None and len(replies) > 1 and is_answer(msg):
                        answers += 1
                        progress(answers, int(cyc))
                elif tag == "D":
                    idle_cycle = int(rest.partition(" ")[0])
                elif tag == "K":
                    sp_low, ramend = (int(v) for v in rest.split())
                elif tag == "E":
                    parts = rest.split()
                    end_cycle, state = int(parts[0]), parts[1]
            rc = proc.wait()
        finally:
            timer.cancel()
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    if killed.is_set():
        raise TargetError(f"simavr job: timed out after {timeout:.0f}s")
    if rc != 0:
        raise TargetError(f"simavr job failed: {first_error_line(err.read_text(errors='replace'))}")
    if state == "missing":
        raise TargetError("simavr job: the harness reported no end")
    steps, marks, busy, tool = read_events(events)
    return ChipRun(replies, steps, marks, busy, end_cycle, state, idle_cycle, tool,
                   ramend - sp_low if ramend and sp_low <= ramend else 0)
