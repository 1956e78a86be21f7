"""The command line's option values, checked in one place before any command runs.

Every numeric option's argparse `type=` is a `Number`: the text becomes an int or a finite float,
then the range check of the same meaning elsewhere runs on it (a scenario TOML key's Param, the
firmware's integer ranges in nnik.machine.ranges, the synthesiser's limits), so a limit given on the
command line is judged exactly as the TOML's.  A bad value, and every other argparse complaint,
is one line `nnik: error: COMMAND: argument --OPT: PROBLEM` and exit 2 (`OneLineParser`).
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from typing import Callable

from nnik.machine import ranges, synth
from nnik.machine.params import Param, value_problem
from nnik.machine.scenario import DATASET, TARGET


class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors as the one `nnik: error:` line (no usage block), exit 2."""

    def error(self, message: str):
        where = self.prog.removeprefix("nnik").strip()
        print(f"nnik: error: {where + ': ' if where else ''}{message}", file=sys.stderr)
        raise SystemExit(2)


@dataclass(frozen=True)
class Number:
    """An argparse type: `kind` (int or float) whose `check` returns a problem or None."""

    kind: type
    check: Callable[[float], str | None]
    name: str = "number"

    @property
    def __name__(self) -> str:  # argparse names a type by it
        return self.name

    def __call__(self, text: str):
        v = self.parse(text)
        problem = self.check(v)
        if problem:
            raise argparse.ArgumentTypeError(problem)
        return v

    def parse(self, text: str):
        try:
            v = int(text, 10) if self.kind is int else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if self.kind is int else 'a number'}, got {text!r}") from None
        if self.kind is float and not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
        return v


def between(lo: float, hi: float, unit: str = "") -> Callable[[float], str | None]:
    return lambda v: None if lo <= v <= hi else f"must be in [{lo:g}, {hi:g}]{unit}, got {v:g}"


def of_param(p: Param) -> Number:
    """The option of a TOML key: its kind, coercion and check (the scenario's own)."""
    kind = int if p.kind == "int" else float
    return Number(kind, lambda v: value_problem(v, p)[1], name=p.kind)


def pair(text: str) -> tuple[float, float]:
    """--offset X,Y: two finite numbers within the largest machine."""
    parts = text.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"needs X,Y (two numbers), not {text!r}")
    out = tuple(OFFSET(p.strip()) for p in parts)
    return out


MAX_TRIALS = 100_000  # a study's finished trials: days of work at the fastest measured rate
MAX_JOBS = 256
TRIALS = Number(int, between(1, MAX_TRIALS), "int")
JOBS = Number(int, between(1, MAX_JOBS), "int")
CLOCK_HZ = Number(int, between(1_000, 1_000_000_000, " Hz"), "int")  # the estimate's clock: 1 kHz..1 GHz
SCALE = Number(float, ranges.scale_problem)
OFFSET = Number(float, ranges.offset_problem)
TOOL_Z = Number(float, ranges.tool_z_problem)
SEG_UM = Number(int, ranges.seg_um_problem, "int")
SYNTH_N = Number(int, between(synth.N_MIN, synth.N_MAX), "int")
NOISE_UM = Number(float, between(0.0, synth.NOISE_UM_MAX, " um"))
INSET_MM = Number(float, between(synth.EDGE_MARGIN_MM, ranges.MAX_LENGTH_MM, " mm"))  # and below half the workspace
SEED = of_param(DATASET["seed"])  # the scenario's [dataset] seed range
MAX_ERROR, MAX_CYCLES, MAX_FLASH_BYTES = (of_param(TARGET[k]) for k in ("max_error", "max_cycles", "max_flash_bytes"))


def path(text: str) -> str:
    """A file or directory argument: never empty (an empty path is the current directory, which
    nobody means), never a NUL byte (no file system takes one)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("needs a path, got an empty one")
    if "\0" in text:
        raise argparse.ArgumentTypeError("a path cannot hold a NUL byte")
    return text


PATH_DESTS = ("scenario", "model_dir", "outdir", "output", "arduino", "job", "source")


def check_paths(parser: argparse.ArgumentParser) -> None:
    """Every file and directory argument of every command (found by its name) takes `path`."""
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for p in a.choices.values():
                check_paths(p)
        elif a.dest in PATH_DESTS and a.type is None and not a.choices:
            a.type = path
