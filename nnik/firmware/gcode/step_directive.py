"""A closed-loop job's raw reference step: the directive line `;@step X25 Y20`.

The seed's step tests are steps of the reference, not planned moves. A closed-loop job (a dc_servo
xy_table, nnik.job.closed_loop) reads a line `;@step` followed by X and/or Y words as `G0 X.. Y..`
would read them (units, G90/G91, work offsets, the job's frame; it leaves the motion mode at G0
as a G0 does), except that the reference jumps to the target at once instead of being planned:
the planned motion before it finishes and comes to rest first, the moves after it start there.
To every other G-code reader it is a comment, so an open-loop machine, which plans every move,
refuses it (`refuse`) rather than silently skip it.
"""

from __future__ import annotations

import re

from nnik.errors import NnikError

DIRECTIVE = re.compile(rb"^\s*;\s*@step\b(.*)$", re.IGNORECASE)
WORDS = re.compile(r"\s*([XY])\s*([-+]?(?:\d+\.?\d*|\.\d+))\s*", re.IGNORECASE)


def is_step(raw: bytes) -> bool:
    return DIRECTIVE.match(raw) is not None


def as_move(raw: bytes, where: str) -> bytes:
    """The directive's target as the G0 line the interpreter reads (where: FILE:LINE for errors)."""
    text = DIRECTIVE.match(raw).group(1).decode("latin-1").strip()
    words, pos = [], 0
    while pos < len(text):
        m = WORDS.match(text, pos)
        if not m or m.end() == pos:
            raise NnikError(f"{where}: ;@step takes X and/or Y words (e.g. ;@step X25 Y20), got {text!r}")
        words.append((m.group(1).upper(), m.group(2)))
        pos = m.end()
    axes = [w for w, _ in words]
    if not words or len(set(axes)) != len(axes):
        raise NnikError(f"{where}: ;@step takes X and/or Y words, each at most once (e.g. ;@step X25 Y20), "
                        f"got {text!r}")
    return ("G0 " + " ".join(f"{a}{v}" for a, v in words)).encode()


def refuse(lines: list[bytes], source: str, machine: str = "this machine") -> None:
    """NnikError at the first step directive: only a closed-loop job commands a raw step."""
    for k, raw in enumerate(lines, 1):
        if is_step(raw):
            raise NnikError(f"{source}:{k}: ;@step (a raw reference step) runs only in a closed-loop job on a "
                            f"dc_servo xy_table; {machine} plans every move: write it as G0/G1")
