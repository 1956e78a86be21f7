"""The one error type of the DC-servo dynamics: a log, a model or an excitation that cannot be
used, as one line. nnik.dynamics imports nothing of nnik's upper rooms (not even nnik.errors:
tests/test_imports_acyclic.py counts levels), so the commands turn it into an NnikError, as
`nnik shaper-calibrate` does with nnik.dynamics.calibrate.CalibrationError."""


class ServoError(ValueError):
    """A problem with a servo log, model or excitation: one line."""
