"""The PIC18 watchdog is off in the harness, and a reset on either chip is an error (issue 11, section 1)."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.targets import float_ik
from nnik.emit.templating import write_sources
from nnik.machine.scenario import load_scenario
from nnik.targets import TargetError
from nnik.targets.pic18 import parse_gpsim_output
from tests.conftest import DATASETS
from tests.targets.runner_helpers import need_toolchain


def test_long_batch_runs_without_a_watchdog_reset(tmp_path):
    """300 float IK calls (~13 M instruction cycles) in one gpsim run: the watchdog (~11.5 M
    cycles) used to restart the program at call 260, pairing later results with the wrong vectors."""
    from nnik.targets import run_on_target

    need_toolchain("pic18")
    scn = load_scenario(DATASETS / "galvo_cba2012.toml")
    write_sources(float_ik.render_float_c(scn), tmp_path)
    src = tmp_path / "galvo_cba2012_float.c"
    vec = np.random.default_rng(0).integers(-100000, 100001, (300, 2))
    one = run_on_target(target="pic18", sources=[src], include_dirs=[tmp_path], name=src.stem, vectors=vec,
                        batch_size=300, workdir=tmp_path / "one", progress=False)
    assert one["cycles"].sum() > 11_500_000
    tail = run_on_target(target="pic18", sources=[src], include_dirs=[tmp_path], name=src.stem, vectors=vec[250:],
                         batch_size=50, workdir=tmp_path / "tail", progress=False)
    assert np.array_equal(one["outputs"][250:], tail["outputs"])
    assert np.array_equal(one["cycles"][250:], tail["cycles"])


def _session(resets: str = "") -> str:
    lines = ["@@S -1", "100 = 0x64", "@@E -1", "110 = 0x6E", "@@S 0", "200 = 0xC8", resets, "@@E 0", "900 = 0x384", "@@R 0"]
    lines += [f"[0x{k:x}] = ${v:02X} = 0b0" for k, v in enumerate([1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0])]
    return "\n".join(lines + ["@@D"])


def test_session_parses():
    out, flags, cycles, _ = parse_gpsim_output(_session(), 1, 2)
    assert out.tolist() == [[1, 2]] and cycles.tolist() == [690]


@pytest.mark.parametrize("text", ["WDT expired reset\nReset on Watch Dog Timer expire\n  Reset: WDT_RESET",
                                  "  Reset: STKOVF_RESET"])
def test_reset_is_an_error(text):
    with pytest.raises(TargetError, match="the chip reset during vector 0"):
        parse_gpsim_output(_session(text), 1, 2)


def test_avr_restart_is_an_error():
    """On the AVR a reset shows as the harness's start-up line twice."""
    from nnik.targets.avr import parse_simavr_output

    one = "@@C 00000010 00000020\n@@V 00000000 00000001 00000002 00000000 00000064\n@@E 00000001\n"
    out, flags, cycles, _ = parse_simavr_output(one, 1, 2)
    assert out.tolist() == [[1, 2]] and cycles.tolist() == [100]
    with pytest.raises(TargetError, match="started twice"):
        parse_simavr_output(one.replace("@@E", "@@C 00000010 00000020\n@@E"), 1, 2)
