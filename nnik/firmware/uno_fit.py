"""The build options the Uno's sender build carries (issue 26 item 6), as grbl's config.h leaves
out what does not fit: UNO_FEATURES less the fewest options, in the order of DROPS, whose build
fits the ATmega328P's flash. The library's header gives the Mega (ATmega2560) every option.

A shaper's code and a large IK table (corexy_nonlinear's table pick with ZVD at 1 kHz, say) can leave
no room for them, or for any option: then nothing fits and the caller says so (docs/firmware.md has
the measured sizes). What is left out answers error:20, as grbl does for
what it was built without, and a build may turn it back on with -D (docs/firmware.md: each
option's flash). Decided by building the sketch (avr-gcc) when the toolchain is there, else the
options stay as they are.
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

DROPS = ((), ("planes",), ("wcs",), ("planes", "wcs"))  # the cheapest loss first: G18/G19 arcs, then G10/G55..


def uno_features(libdir: Path, name: str, machine) -> tuple[frozenset, tuple[str, ...], int]:
    """(the options the Uno's sender build carries, those left out, its flash in B; 0: not built;
    -1: no choice of options fits the Uno, the build is for the ATmega2560)."""
    from nnik.firmware.gcode import chip
    from nnik.targets.toolchain import TargetError

    if not chip.available()[0]:
        return frozenset(machine.features), (), 0
    with tempfile.TemporaryDirectory(prefix="nnik-uno-fit-") as tmp:
        for drop in DROPS:
            cfg = replace(machine, features=frozenset(machine.features) - set(drop))
            try:
                fw = chip.build_sketch(libdir, f"{name}_gcode", Path(tmp), cfg.defines(), mcu="atmega328p")
            except TargetError as exc:
                if "does not fit" not in str(exc):
                    raise
                continue
            return cfg.features, tuple(d for d in drop if d in machine.features), fw.flash_bytes
    return frozenset(machine.features), (), -1  # nothing fits: the Uno cannot carry this machine
