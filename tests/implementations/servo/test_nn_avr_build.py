"""The neural controllers' C builds for the ATmega328P (avr-gcc -Os, warnings as errors) with every
learning-rate shift and schedule: the inline-assembly blocks' register needs and byte shifts depend
on eta_shift, so each value is compiled."""

from __future__ import annotations

import subprocess

import pytest

from nnik.implementations.servo import NEURAL, make
from nnik.implementations.servo.emit_c import write_controller_c
from nnik.implementations.servo.nn import formats as f
from nnik.targets.avr import compile_flags
from tests.conftest import require_tool
from tests.implementations.servo.nn_params import seeded_nn_params
from tests.implementations.servo.sequences import CFG


@pytest.mark.parametrize("kind", NEURAL)
def test_every_learning_rate_builds_for_the_avr(kind, tmp_path):
    require_tool("avr-gcc")
    for eta in range(f.ETA_MAX + 1):
        p = {**seeded_nn_params(kind, eta, CFG, eta_shift=eta), "w1_every": (1, 2, 4, 8)[eta % 4],
             "in_shift": [eta % 25 - 12, 0, 12, -(eta % 13)]}
        d = tmp_path / f"eta{eta}"
        src = [s for s in write_controller_c(make(kind, p, CFG), d) if s.name == f"nnik_ctl_{kind}.c"][0]
        r = subprocess.run(["avr-gcc", *compile_flags("-Os", ["-Wall", "-Wextra", "-Werror"]), "-I", str(d), "-c",
                            str(src), "-o", str(d / "out.o")], capture_output=True, text=True)
        assert r.returncode == 0, f"eta_shift {eta}: {r.stderr.strip()[:400]}"
