"""The reference's history over a window of W ticks (W a power of 2, at most 8): the PD +
feedforward's speed and acceleration and the cross-coupled controller's path direction come from
differences over W ticks rather than one, so that a reference rounded to whole counts still gives a
usable speed at low feeds (at 1 mm/s the reference moves 2 counts a tick). A reset fills the history
with the first reference seen (the table was at rest there). The C (a ring of 2W int32 per axis)
repeats it."""

from __future__ import annotations

from nnik.errors import NnikError

WINDOWS = (1, 2, 4, 8)


def check_window(win) -> int:
    if win not in WINDOWS:
        raise NnikError(f"controller window must be one of {', '.join(map(str, WINDOWS))} ticks, not {win!r}")
    return int(win)


class RefHistory:
    """ref[k - W] and ref[k - 2W] for one axis."""

    def __init__(self, win: int):
        self.win = win
        self.ring: list[int] | None = None
        self.idx = 0

    def reset(self) -> None:
        self.ring, self.idx = None, 0

    def push(self, ref: int) -> tuple[int, int]:
        """(ref[k - W], ref[k - 2W]) and record ref as ref[k]."""
        n = 2 * self.win
        if self.ring is None:
            self.ring = [ref] * n
        old2, old1 = self.ring[self.idx], self.ring[(self.idx + self.win) & (n - 1)]
        self.ring[self.idx] = ref
        self.idx = (self.idx + 1) & (n - 1)
        return old1, old2
