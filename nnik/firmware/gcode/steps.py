"""Step events: the DDA's, from the Python model, and the chip's, from the recorded pins.

An event is (segment, tick, motor, dir): tick 1..N within its segment (the stepper interrupt
that starts a segment is its tick 1), dir 1 for a positive step. The DDA is the firmware's
centred Bresenham: acc = N // 2, each tick acc += |d|, a step when acc >= N (acc -= N), so
step k of a segment falls on tick ceil((k N - N // 2) / |d|).
"""

from __future__ import annotations

import numpy as np

from nnik.firmware.gcode.motion import Segments


def model_events(seg: Segments) -> np.ndarray:
    """(K, 4) int64 events of every segment, sorted (segment, tick, motor)."""
    parts = []
    n = seg.ticks
    for motor in range(2):
        a = np.abs(seg.delta[:, motor])
        s_idx = np.repeat(np.arange(len(a)), a)
        if not len(s_idx):
            continue
        start = np.concatenate([[0], np.cumsum(a)[:-1]])
        k = np.arange(len(s_idx)) - np.repeat(start, a) + 1
        N, A = n[s_idx], a[s_idx]
        tick = -((-(k * N - N // 2)) // A)  # ceil
        d = (seg.delta[s_idx, motor] > 0).astype(np.int64)
        parts.append(np.stack([s_idx, tick, np.full_like(s_idx, motor), d], 1))
    ev = np.concatenate(parts) if parts else np.zeros((0, 4), np.int64)
    return ev[np.lexsort((ev[:, 2], ev[:, 1], ev[:, 0]))]


def chip_events(steps: np.ndarray, marks: np.ndarray, tick_cycles: int) -> np.ndarray:
    """(K, 4) events from recorded step edges (cycle, motor, dir) and segment-start cycles."""
    if not len(steps):
        return np.zeros((0, 4), np.int64)
    seg = np.searchsorted(marks, steps[:, 0], side="right") - 1
    if (seg < 0).any():
        raise ValueError("a step before the first segment marker")
    tick = np.rint((steps[:, 0] - marks[seg]) / tick_cycles).astype(np.int64) + 1
    ev = np.stack([seg, tick, steps[:, 1], steps[:, 2]], 1)
    return ev[np.lexsort((ev[:, 2], ev[:, 1], ev[:, 0]))]


def model_tool_events(seg: Segments) -> np.ndarray:
    """(T, 3) int64 tool changes: (segment, tick 1, duty) wherever a segment's duty differs
    from the one before it (0 before the first)."""
    duty = np.asarray(seg.duty, dtype=np.int64)
    prev = np.concatenate([[0], duty[:-1]])
    k = np.flatnonzero(duty != prev)
    return np.stack([k, np.ones_like(k), duty[k]], 1).reshape(-1, 3)


def chip_tool_events(tool: np.ndarray, marks: np.ndarray, tick_cycles: int) -> np.ndarray:
    """(T, 3) tool changes from the recorded PWM (cycle, duty) and segment-start cycles: the
    segment and the tick within it in which the duty changed."""
    tool = np.asarray(tool, dtype=np.int64).reshape(-1, 2)
    seg = np.searchsorted(marks, tool[:, 0], side="right") - 1
    if (seg < 0).any():
        raise ValueError("a tool change before the first segment marker")
    tick = (tool[:, 0] - marks[seg]) // tick_cycles + 1
    return np.stack([seg, tick, tool[:, 1]], 1).reshape(-1, 3)


def positions(seg: Segments, events: np.ndarray) -> np.ndarray:
    """Actuator counts after each event, (K + 1, 2), from the start command."""
    inc = np.zeros((len(events), 2), np.int64)
    inc[np.arange(len(events)), events[:, 2]] = np.where(events[:, 3] == 1, 1, -1)
    return seg.steps[0] + np.concatenate([np.zeros((1, 2), np.int64), np.cumsum(inc, axis=0)])
