"""The one error type users see: a single clear line, exit code 2."""


class NnikError(Exception):
    """A problem with the user's input or model, reported as one line (CLI exit code 2)."""

    def __init__(self, message: str, source: str | None = None, key: str | None = None):
        self.source = source
        self.key = key
        parts = [str(p) for p in (source, key) if p]
        prefix = ": ".join(parts)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class NnikWarning(UserWarning):
    """A problem nnik works around, reported as one `nnik: warning: ...` line (the run goes on)."""


def warning_line(w) -> str:
    """The stderr line of a caught warning: an NnikWarning as it reads, others with their type and
    where they arose."""
    from pathlib import Path

    if issubclass(w.category, NnikWarning):
        return f"nnik: warning: {w.message}"
    return f"nnik: warning: {w.category.__name__}: {w.message} ({Path(w.filename).name}:{w.lineno})"
