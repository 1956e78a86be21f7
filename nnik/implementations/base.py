"""One interface for an IK implementation, as :class:`nnik.machine.kinematics.base.Mechanism` serves
every machine. A family (``mlp``, ``poly``, ``lut``, ``hybrid``) is one small module in this
package with one :class:`Implementation` subclass:

* ``ladder(problem)``: a small built-in list of configurations (knob settings), cheapest first,
  that ``nnik run`` tries;
* ``fit(problem, config)``: fit on the problem's data (numpy, scipy, scikit-learn or torch);
* ``run(in_units)``: the integer model in numpy, the bit-exact oracle of the C
  (-> :class:`IntRun`: pre-rounding value, delivered output, clamp flag);
* ``render_c()``: ``{"NAME.h": ..., "NAME.c": ...}`` under the contract of
  :mod:`nnik.implementations.problem` (one function ``NAME_ik``); a fast path on the AVR and
  PIC18 hardware multipliers where it pays, and a portable C99 path with identical bits
  (``-DNNIK_PORTABLE`` selects it on any compiler);
* ``estimate(target)``: static cost on ``avr`` / ``pic18`` (cycles, flash, RAM) and whether the
  model behind it was validated against the simulators;
* ``describe()`` / ``config``: a one-line human label and the knobs as a JSON-able dict.

Verification (host with sanitizers, simavr, gpsim) is shared by every family in
:mod:`nnik.implementations.verify`; accuracy on the dense check grid in
:mod:`nnik.implementations.accuracy`.
"""

from __future__ import annotations

import hashlib
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from nnik.implementations.problem import Problem

TARGETS = ("avr", "pic18")


@dataclass
class IntRun:
    """The integer model's result for N inputs."""

    pre: np.ndarray  # (N, 2) float64: the value before rounding, in output units (exact: num / 2^s + offset)
    out: np.ndarray  # (N, 2) int64: what the C returns in out[]
    flags: np.ndarray  # (N,) int64: what the C returns (1 if an input was clamped)


class Implementation(ABC):
    family: ClassVar[str]
    doc: ClassVar[str] = ""
    # chips on which the portable C path (-DNNIK_PORTABLE) is verified too, besides the host
    portable_checked_on: ClassVar[tuple[str, ...]] = TARGETS
    portable_not_checked_reason: ClassVar[str] = ""
    # chips where the search verifies this family's front points besides its best (the best is
    # verified on every chip)
    front_checked_on: ClassVar[tuple[str, ...]] = TARGETS
    front_not_checked_reason: ClassVar[str] = ""
    # a config knob the ladder grows (e.g. a polynomial's degree): selection.fit_ladder stops a
    # family's ladder once STALL_STEPS values of it in a row no longer improve the family's error
    grows_by: ClassVar[str | None] = None
    # a config knob whose values each grow ``grows_by`` separately (the polynomial's width: its
    # 32-bit degrees do not stall on the 16-bit ones' errors)
    grows_within: ClassVar[str | None] = None

    def __init__(self, problem: Problem, config: dict):
        self.problem = problem
        self.config = dict(config)

    # ---- fitting -----------------------------------------------------------------------------
    @classmethod
    @abstractmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        """Configurations ``nnik run`` tries, roughly cheapest first."""

    @classmethod
    @abstractmethod
    def fit(cls, problem: Problem, config: dict) -> "Implementation":
        """Fit one configuration. Raise :class:`nnik.errors.NnikError` when it cannot be built
        (e.g. does not fit int32); the caller skips it and records why."""

    # ---- the integer model and its C ------------------------------------------------------------
    @abstractmethod
    def run(self, in_units: np.ndarray) -> IntRun:
        """Bit-exact model of the C for (N, 2) int64 inputs (any values, clamped like the C)."""

    @abstractmethod
    def render_source(self) -> str:
        """The text of ``NAME.c`` (``NAME = problem.name``); it includes ``"NAME.h"``, which
        :meth:`render_c` writes from the shared template ``codegen/templates/ik.h.j2``."""

    def render_c(self) -> dict[str, str]:
        """``{"NAME.h": ..., "NAME.c": ...}``."""
        from nnik.implementations.c_common import render_header

        name = self.problem.name
        return {f"{name}.h": render_header(self), f"{name}.c": self.render_source()}

    # ---- cost -------------------------------------------------------------------------------------
    @abstractmethod
    def estimate(self, target: str) -> dict:
        """``{"cycles": float, "flash_bytes": int, "ram_bytes": int, "validated": bool}`` on
        ``target`` (``avr``: avr-gcc -Os, CPU cycles; ``pic18``: SDCC, instruction cycles)."""

    @abstractmethod
    def model_bytes(self) -> int:
        """Bytes of constants (tables, coefficients, weights) the C keeps in flash."""

    def describe(self) -> str:
        return f"{self.family} " + ", ".join(f"{k}={v}" for k, v in self.config.items())

    def source_hash(self) -> str:
        """Hash of the emitted NAME.c: the identity every stored verification result is keyed to
        (the header quotes it)."""
        if "_source_hash" not in self.__dict__:
            self._source_hash = hashlib.sha256(self.render_source().encode()).hexdigest()[:16]
        return self._source_hash
