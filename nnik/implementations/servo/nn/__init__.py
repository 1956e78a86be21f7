"""The seed's online-learning neural controllers (issue 29) as integer Python models of
codegen/arduino/src/nnik_ctl_nn_axes.c / nnik_ctl_nn_vector.c (shared network: nnik_ctl_nn.h), bit
for bit: nn_axes (one 4-8-1 net per axis, nn_axes.py) and nn_vector (one net on the contour error's
magnitude, nn_vector.py). Formats: formats.py; params keys: params.py; the network: net.py."""

from __future__ import annotations

from nnik.implementations.servo.nn.params import NETS, check_params, initial_params, jacobian_q

KINDS = tuple(NETS)
__all__ = ["KINDS", "check_params", "initial_params", "jacobian_q"]
