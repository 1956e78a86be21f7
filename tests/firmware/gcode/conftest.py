"""The G-code firmware on the simulated Uno, built once per session for every test that runs it."""

from __future__ import annotations

import os

import numpy as np
import pytest

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.firmware.gcode import chip
from nnik.firmware.ik_oracle import ik_oracle
from tests.conftest import require_tool

# the motion pin falls in the last tick's interrupt, within this many cycles of the point where
# the segment marker toggled in its first tick's interrupt (one tick is 1600 cycles)
IDLE_SLACK_CYCLES = 200


def require_chip() -> None:
    """Skip without avr-gcc, simavr and the Arduino core (fail under NNIK_REQUIRE_TOOLCHAINS=1)."""
    for tool in ("avr-gcc", "avr-g++", "simavr"):
        require_tool(tool)
    why = chip.tool_missing_reason()
    if why:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(why)
        pytest.skip(why)


@pytest.fixture(scope="session")
def tool_firmware(corexy_run, tmp_path_factory):
    """cfg -> corexy_nonlinear's G-code firmware built for cfg's tool (entries as in firmware),
    built once per tool setting in a session."""
    require_chip()
    pipeline.export(corexy_run)
    built = {}

    def get(cfg):
        key = tuple(sorted(cfg.defines().items()))
        if key not in built:
            work = tmp_path_factory.mktemp("tool")
            lib = dict(export_arduino(corexy_run, work / "lib", cfg))
            fw = chip.build_sketch(work / "lib", "corexy_nonlinear_gcode", work / "build", chip.file_run_defines(cfg))
            built[key] = (corexy_run, lib, fw, ik_oracle(corexy_run), work / "build")
        entry = built[key]
        return (entry[0], {**entry[1], "machine": cfg}, *entry[2:])

    return get


@pytest.fixture(scope="session")
def pen_firmware(corexy_run, tool_firmware):
    """corexy_nonlinear's G-code firmware for a servo pen (Z > 0.25 mm: up)."""
    from dataclasses import replace

    from nnik.firmware.config import default_machine
    from nnik.firmware.ik_oracle import load_scenario_of

    return tool_firmware(replace(default_machine(load_scenario_of(corexy_run)), tool="servo", pen_z_um=250,
                                 bounds_um=None))


@pytest.fixture(scope="session")
def firmware(galvo_run, corexy_run, tmp_path_factory):
    """Per scenario: (model dir, library info, the built G-code firmware, the IK oracle, build dir)."""
    from dataclasses import replace

    require_chip()
    out = {}
    for name, run in (("galvo_cba2012", galvo_run), ("corexy_nonlinear", corexy_run)):
        pipeline.export(run)
        work = tmp_path_factory.mktemp(name)
        lib = export_arduino(run, work / "lib")
        # random jobs wander beyond the travel: soft limits off here (ALARM:2 has its own tests)
        lib = {**lib, "machine": replace(lib["machine"], bounds_um=None)}
        fw = chip.build_sketch(work / "lib", f"{name}_gcode", work / "build", chip.file_run_defines(lib["machine"]))
        out[name] = (run, lib, fw, ik_oracle(run), work / "build")
    return out


@pytest.fixture(scope="session")
def zvd_firmware(firmware, tmp_path_factory):
    """Per scenario: the G-code firmware with ZVD input shaping for 40 Hz, zeta 0.1 on both axes
    (entries as in firmware)."""
    from dataclasses import replace

    from nnik.firmware.config import shaper_taps

    out = {}
    for name, (run, lib, _, ik, _) in firmware.items():
        # the shipped jobs' own build, as `nnik job` makes it: no option they do not use (the Uno's
        # sender build with ZVD leaves options out to fit: nnik.firmware.uno_fit)
        cfg = replace(lib["machine"], features=frozenset())
        cfg = replace(cfg, shaper="zvd", shaper_taps=shaper_taps("zvd", {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)},
                                                                   cfg.sample_hz))
        work = tmp_path_factory.mktemp(f"{name}_zvd")
        lib2 = export_arduino(run, work / "lib", cfg)
        fw = chip.build_sketch(work / "lib", f"{name}_gcode", work / "build", chip.file_run_defines(cfg))
        out[name] = (run, lib2, fw, ik, work / "build")
    return out


@pytest.fixture(scope="session")
def hump_firmware(firmware, tmp_path_factory):
    """The CoreXY G-code firmware with a shaper per axis as a [shaper] table gives it: 3HUMP_EI
    at 45 Hz (zeta 0.1) on X, 2HUMP_EI at 38 Hz (zeta 0.15) on Y (entries as in firmware)."""
    from dataclasses import replace

    from nnik.firmware.config import axis_shapers

    run, lib, _, ik, _ = firmware["corexy_nonlinear"]
    table = {"type": ("3hump_ei", "2hump_ei"), "freq_hz": (45.0, 38.0), "damping": (0.1, 0.15), "label": "3hump_ei/2hump_ei"}
    cfg = replace(lib["machine"], features=frozenset())  # the shipped jobs' own build, as in zvd_firmware
    taps, designs = axis_shapers(table["label"], None, table, cfg.sample_hz)
    cfg = replace(cfg, shaper=table["label"], shaper_taps=taps, shaper_design=designs)
    work = tmp_path_factory.mktemp("corexy_hump")
    lib2 = export_arduino(run, work / "lib", cfg)
    fw = chip.build_sketch(work / "lib", "corexy_nonlinear_gcode", work / "build", chip.file_run_defines(cfg))
    return run, lib2, fw, ik, work / "build"


def run_both(entry, lines: list[str], protocol: str = "send-response", sent: list[str] | None = None,
             clean: bool = True):
    """The lines through the Python model and the simulated chip: (plan, segments, chip run), with
    the chip's answers, segments and every step checked against the model's, and the run's end
    checked to fall when the last segment's last tick is over, however the job ends. protocol:
    how the harness streams them (chip.PROTOCOLS); sent: the chip's lines if not lines (the same
    lines as the firmware reads them); clean: chip.sent_lines's."""
    from nnik.firmware.gcode.chip import CLOCK_HZ
    from nnik.firmware.gcode.motion import interpret, plan_steps
    from nnik.firmware.gcode.steps import chip_events, chip_tool_events, model_events, model_tool_events

    _, lib, fw, ik, work = entry
    cfg = lib["machine"]
    plan = interpret(lines, cfg)
    seg = plan_steps(plan, cfg, ik)
    res = chip.run_firmware(fw, lines if sent is None else sent, work, 2.0 + 1.5 * seg.ticks.sum() / cfg.tick_hz,
                            protocol=protocol, clean=clean)
    assert res.state == "done"
    assert 0 < res.stack_bytes and fw.ram_bytes + res.stack_bytes <= chip.RAM_BYTES  # the stack never met the data
    assert [t for _, t in res.replies if not t.startswith(("nnik ", "Grbl ")) and t] == plan.replies
    assert len(res.marks) == len(seg.ticks)
    tick = CLOCK_HZ // cfg.tick_hz
    got, want = chip_events(res.steps, res.marks, tick), model_events(seg)
    assert got.shape == want.shape and np.array_equal(got, want)
    got, want = chip_tool_events(res.tool, res.marks, tick), model_tool_events(seg)
    assert got.shape == want.shape and np.array_equal(got, want), (got, want)  # each on its segment's first tick
    if len(seg.ticks):
        last_tick = int(res.marks[-1]) + (int(seg.ticks[-1]) - 1) * tick  # the interrupt of its last tick
        assert abs(res.idle_cycle - last_tick) < IDLE_SLACK_CYCLES, res.idle_cycle - last_tick
    else:
        assert res.idle_cycle == 0
    return plan, seg, res
