"""Progress bars for long work, on a terminal only: a log file or a pipe gets no carriage-return
bar updates (which would pile up on one line, with the next error line glued to them)."""

from __future__ import annotations

import sys

from tqdm import tqdm


def on_terminal() -> bool:
    return sys.stderr.isatty()


def bar(iterable=None, *, disable: bool = False, **kw) -> tqdm:
    """A tqdm bar on stderr, silent when `disable` or when stderr is not a terminal."""
    return tqdm(iterable, disable=disable or not on_terminal(), **kw)
