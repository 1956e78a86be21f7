"""A closed-loop job's loop: the reference through the controller against the plant, in Python
(nnik.dynamics.servo.closed_loop.simulate: the controller's integer model and the scenario's true
plant), and on the simulated Uno when the toolchain is there (nnik.firmware.servo.cosim: the
controller's C on simavr, lockstep with the same plant; chip = model tick by tick).

Reference + controller -> Looped: the Python trace, a learning controller's weight clamps and
updates over the job (learning_figures), and the chip's figures (or why it did not run).
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
    learning: dict | None = None  # a learning controller's clamps and updates (learning_figures); None: fixed gains


# a run whose weight clamps pass this fraction of its weight updates is flagged as diverged (issue 29)
DIVERGED_CLAMP_FRACTION = 0.01


def learning_figures(controller) -> dict | None:
    """A learning controller's weight updates and clamps since its reset, the clamps' share, the
    diverged flag (clamps > DIVERGED_CLAMP_FRACTION of the updates) and its weights' checksum; None
    for a controller without weights (pid, pdff, ccc)."""
    if not hasattr(controller, "clamps"):
        return None
    clamps, updates = int(controller.clamps), int(controller.updates)
    return {"updates": updates, "clamps": clamps, "clamp_pct": 100.0 * clamps / updates if updates else 0.0,
            "diverged": clamps > DIVERGED_CLAMP_FRACTION * updates, "checksum": int(controller.checksum())}


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
    learning = learning_figures(controller)  # before the co-simulation resets it
    why = chip_missing()
    if use_chip is False or (use_chip is None and why):
        return Looped(trace, {"not_run": "not asked" if use_chip is False else why}, learning)
    if why:
        raise NnikError(f"avr: {why}")
    from nnik.firmware.servo import cosim
    from nnik.firmware.servo.build import build_firmware
    from nnik.targets.toolchain import TargetError

    try:
        fw = build_firmware(controller, cfg.tick_s, work)
        co = cosim.run(fw, cfg, controller, ref.counts, work, start_counts=tuple(int(c) for c in ref.counts[0]))
    except TargetError as exc:
        raise NnikError(f"avr: {exc}") from None
    return Looped(trace, chip_figures(co, fw, trace), learning)


def chip_figures(co, fw, trace: Trace) -> dict:
    """What the chip did: its duty against the model's (mismatches), the plant it drove against the
    Python loop's (the same motion when chip = model and no edge is lost), cycles and load."""
    return {"mismatches": co.mismatches, "first_mismatch_tick": int(co.mismatch_ticks[0]) if co.mismatches else None,
            "checksum_mismatches": int((co.chip_sum != co.model_sum).sum()),
            "lost_count_ticks": co.lost_counts,
            "same_motion_as_the_model": bool((co.plant_counts == trace.counts).all()),
            "controller_cycles_max": co.cycles_max, "tick_isr_cycles_max": int(co.tick_isr_cycles.max()),
            "tick_cycles_max": int(co.awake_cycles.max()), "encoder_isrs_max": int(co.enc_isrs.max()),
            "cpu_pct_max": co.load_pct_max, "period_cycles": co.period_cycles,
            "flash_bytes": fw.flash_bytes, "ram_bytes": fw.ram_bytes}
