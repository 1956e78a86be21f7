"""The closed-loop XY table's baseline controllers (issue 28): integer Python models of the C in
codegen/arduino/src/nnik_ctl_*.c, bit for bit. `make(kind, gains, cfg)` builds one; tune.py tunes
them against the identified model.

- pid:  the Arduino PID library's PID per axis (pid.py)
- pdff: PD with velocity and acceleration feedforward per axis (pdff.py)
- ccc:  Koren's cross-coupled controller, a PID per axis plus a PD on the contour error (ccc.py)
- nn_axes, nn_vector: the seed's online-learning neural controllers (nn/); their "gains" are the
  params dict of nn/params.py (integer weights and formats)
"""

from __future__ import annotations

from nnik.errors import NnikError
from nnik.implementations.servo.base import ServoController

BASELINES = ("pid", "pdff", "ccc")  # tuned (tune.py)
NEURAL = ("nn_axes", "nn_vector")  # pretrained, learning online (nn/)
KINDS = BASELINES + NEURAL
__all__ = ["BASELINES", "KINDS", "NEURAL", "ServoController", "make"]


def make(kind: str, gains: dict, cfg) -> ServoController:
    """The controller `kind` with `gains` (physical units, see each module) for cfg's tick and duty
    range (cfg: a ServoConfig, or anything with tick_s and duty_max)."""
    if kind == "pid":
        from nnik.implementations.servo.pid import Pid
        return Pid(gains, cfg.tick_s, cfg.duty_max)
    if kind == "pdff":
        from nnik.implementations.servo.pdff import Pdff
        return Pdff(gains, cfg.tick_s, cfg.duty_max)
    if kind == "ccc":
        from nnik.implementations.servo.ccc import Ccc
        return Ccc(gains, cfg.tick_s, cfg.duty_max)
    if kind == "nn_axes":
        from nnik.implementations.servo.nn.nn_axes import NnAxes
        return NnAxes(gains, cfg)
    if kind == "nn_vector":
        from nnik.implementations.servo.nn.nn_vector import NnVector
        return NnVector(gains, cfg)
    raise NnikError(f"unknown controller kind {kind!r} (known: {', '.join(KINDS)})")
