"""The one error type users see: a single clear line, exit code 2."""


class NnikError(Exception):
    """A problem with the user's input or model, reported as one line (CLI exit code 2)."""

    def __init__(self, message: str, source: str | None = None, key: str | None = None):
        self.source = source
        self.key = key
        parts = [str(p) for p in (source, key) if p]
        prefix = ": ".join(parts)
        super().__init__(f"{prefix}: {message}" if prefix else message)
