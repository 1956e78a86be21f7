"""The servo controllers' common interface (docs: /docs/closed_loop.md "Controllers").

A controller is duck-typed: `kind`, `reset()`, `tick(ref, pos) -> (duty_x, duty_y)`,
`c_defines()` (the gains and formats as C macros for the generated nnik_servo_config.h) and
`checksum()` (the sum of its weights' int32 master words modulo 2^16 after the last tick, which the
chip reports as nnik_ctl_sum, published by the runtime as nnik_servo_sum; 0 for the fixed-gain controllers, FixedGains). Each tick
it sees the reference and the encoder counts (int32 counts per axis) and returns the duty the plant
holds until the next tick. Its integer arithmetic is the specification of the C in
codegen/arduino/src/nnik_ctl_<kind>.c, which matches it bit for bit.

Gains are given in physical units (floats) and quantised once, when the controller is made; the
quantised values are what both the Python model and the C use.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from nnik.errors import NnikError

# the integral (Q16 duty, three times duty_max with the step being added) must fit in int32
DUTY_MAX_LIMIT = 4095


@runtime_checkable
class ServoController(Protocol):
    kind: str

    def reset(self) -> None: ...

    def tick(self, ref: tuple[int, int], pos: tuple[int, int]) -> tuple[int, int]: ...

    def c_defines(self) -> dict[str, int]: ...

    def checksum(self) -> int: ...


class FixedGains:
    """A controller that does not learn (pid, pdff, ccc): no weights, checksum 0, as its chip's
    nnik_servo_sum (never set) reads."""

    def checksum(self) -> int:
        return 0


def check_gains(kind: str, gains: dict, names: tuple[str, ...], optional: dict[str, float]) -> dict:
    """gains with the optional keys defaulted; one NnikError line for a missing or unknown key."""
    if not isinstance(gains, dict):
        raise NnikError(f"{kind} gains must be a table of numbers, not {type(gains).__name__}")
    unknown = sorted(set(gains) - set(names) - set(optional))
    if unknown:
        raise NnikError(f"{kind} gains: unknown key {unknown[0]!r} (known: {', '.join(names + tuple(optional))})")
    missing = [n for n in names if n not in gains]
    if missing:
        raise NnikError(f"{kind} gains: missing {missing[0]!r}")
    return {**optional, **gains}


def check_duty_max(duty_max: int) -> int:
    if not (isinstance(duty_max, int) and 1 <= duty_max <= DUTY_MAX_LIMIT):
        raise NnikError(f"controller duty_max must be an integer in 1 .. {DUTY_MAX_LIMIT} (12-bit PWM), not {duty_max!r}")
    return duty_max
