"""A job as the interpreter leaves it: its moves and the planner operations behind them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

POS_LIMIT = 2**28 - 1  # um
TOOL_SCALED = 0x100  # a tool word: duty | TOOL_SCALED (M4: duty * the segment's speed / feed)
MIN_FEED = 1000  # um/min


@dataclass(frozen=True)
class Move:
    """One programmed move: a line or an arc (centre, radius, direction), in program um."""

    line_no: int
    kind: str  # "line" | "arc" | "poly"
    start: tuple[int, int]
    end: tuple[int, int]
    first_seg: int  # index of its first planner block (push)
    n_seg: int  # its blocks
    center: tuple[int, int] | None = None
    radius: int = 0
    ccw: bool = True
    rapid: bool = False
    points: tuple = ()  # "poly": the exact path, sampled (a G5 curve, an arc in G18/G19 seen in XY)


@dataclass
class Plan:
    """A whole job as planner operations, before the planner and the IK."""

    ends: list[tuple[int, int]] = field(default_factory=list)  # block ends, um (machine less the origin)
    feed: list[int] = field(default_factory=list)  # um/min of each block
    tool: list[int] = field(default_factory=list)  # the tool word of each block
    dwell: list[int] = field(default_factory=list)  # ticks of each rest (G4, or 1: a tool change)
    ops: list[tuple] = field(default_factory=list)  # ("push", x, y, feed, tool, i), ("flush",), ("rest", ticks, tool)
    moves: list[Move] = field(default_factory=list)
    replies: list[str] = field(default_factory=list)  # "ok", "error:N", "ALARM:N" or "$" (a $ line)
    seg_move: np.ndarray | None = None  # set by plan_steps: the move of every stepper segment


