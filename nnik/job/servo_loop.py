"""A closed-loop job's loop: the reference through the controller against the plant, in Python
(nnik.dynamics.servo.closed_loop.simulate: the controller's integer model and the scenario's true
plant), and on the simulated Uno when the toolchain is there (nnik.firmware.servo.cosim: the
controller's C on simavr, lockstep with the same plant; chip = model tick by tick).

Reference + controller -> Looped: the Python trace, and the chip's figures (or why it did not run).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from nnik.dynamics.servo.closed_loop import Trace, simulate
from nnik.job.reference import Reference


@dataclass
class Looped:
    trace: Trace  # what the table did (the chip's duties are checked equal to the model's)
    chip: dict  # mismatches, cycles per tick, CPU %; or {"not_run": why}


def chip_missing() -> str | None:
    """Why the chip cannot run the loop here (None: it can)."""
    try:
        from nnik.firmware.servo import cosim  # noqa: F401
    except ImportError:
        return "the closed-loop co-simulation is not in this build (nnik.firmware.servo)"
    from nnik.firmware.gcode import chip

    return chip.tool_missing_reason()


def loop(ref: Reference, cfg, controller, work: Path, use_chip: bool | None) -> Looped:
    from nnik.errors import NnikError

    trace = simulate(cfg, controller, ref.counts)
    why = chip_missing()
    if use_chip is False or (use_chip is None and why):
        return Looped(trace, {"not_run": "not asked" if use_chip is False else why})
    if why:
        raise NnikError(f"avr: {why}")
    from nnik.firmware.servo import cosim

    co = cosim.run(cosim.build(cfg, controller, work), cfg, controller, ref.counts)
    return Looped(trace, cosim.figures(co))
