"""Real G-code files that other tools wrote (tests/data/gcode/real/, origins in SOURCES.md), each on
the galvo, the CoreXY laser and a CoreXY pen plotter, with --fit: a file grbl runs runs with
nothing clamped; a file with what these machines cannot honour is refused at its first such line
with the error number that names it (EXPECTED.toml says which, from a grbl user's point of view)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from nnik.errors import NnikError
from nnik.firmware.gcode.motion import plan_steps
from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
from nnik.firmware.gcode.reader import sendable
from nnik.firmware.ik_oracle import ik_oracle, load_scenario_of
from nnik.job.parse import machine_for
from nnik.job.plan import interpret

REAL = Path(__file__).resolve().parents[2] / "data" / "gcode" / "real"
EXPECTED = tomllib.loads((REAL / "EXPECTED.toml").read_text())
REASON_CODE = {"named-parameters": 41, "expressions": 41, "o-word-subroutine": 42, "probing": 43, "extra-axis": 20,
               "canned-cycle": 20, "other:checksum-mismatch": 40, "other:nested-comment": 1}
MACHINES = ("galvo", "corexy", "pen")


def test_the_corpus_is_what_the_issue_asks():
    files = sorted(p.name for p in REAL.iterdir() if p.name not in ("SOURCES.md", "EXPECTED.toml"))
    assert files == sorted(EXPECTED) and len(files) >= 20
    sources = (REAL / "SOURCES.md").read_text()
    assert all(f in sources for f in files)
    assert sum(e["outcome"] == "run" for e in EXPECTED.values()) >= 18
    assert {e["flavour"] for e in EXPECTED.values()} == {"grbl", "marlin", "linuxcnc"}


@pytest.fixture(scope="module")
def machines(galvo_run, corexy_run):
    out = {}
    for name, run in (("galvo", galvo_run), ("corexy", corexy_run), ("pen", corexy_run)):
        cfg = machine_for(load_scenario_of(run), "none", None)
        out[name] = (run, cfg, JobOptions(fit=True, tool="pen" if name == "pen" else None))
    return out


@pytest.mark.parametrize("machine", MACHINES)
@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_file_runs_or_is_refused_by_name(machines, name, machine):
    run, cfg, opts = machines[machine]
    e = EXPECTED[name]
    lines = read_job(REAL / name)
    if e["outcome"] == "refuse":
        with pytest.raises(NnikError) as err:
            prepare(lines, cfg, opts, name)
        assert f"{name}:{e['line']}: error:{REASON_CODE[e['reason']]} " in str(err.value)
        return
    prep = prepare(lines, cfg, opts, name)
    assert prep.summary["flavour"] == e["flavour"]
    plan = interpret([sendable(ln).decode("latin-1") for ln in prep.lines], prep.cfg, name, prep.line_of)
    seg = plan_steps(plan, prep.cfg, ik_oracle(run))
    assert set(plan.replies) <= {"ok"}
    assert int(seg.clamped.sum()) == 0  # the job was fitted, never clamped
    if seg.ends_um.size:
        (x0, y0), (x1, y1) = prep.cfg.bounds_um
        assert x0 <= seg.ends_um[:, 0].min() and seg.ends_um[:, 0].max() <= x1
        assert y0 <= seg.ends_um[:, 1].min() and seg.ends_um[:, 1].max() <= y1
    if machine == "pen" and e["tool_rule"] in ("z", "s", "e"):
        assert prep.summary["tool_rule"] == e["tool_rule"]
    assert np.all(seg.ticks > 0)


@pytest.mark.parametrize("name, machine", [("linuxcnc_skeleton.ngc", "corexy"), ("slic3r_sample.gcode", "pen"),
                                           ("cncjs_spaces.nc", "galvo")])
def test_short_files_on_the_simulated_uno(machines, name, machine):
    """`nnik job --fit` on the chip: its build carries what the file uses, and every step, answer
    and tool change equals the model's."""
    from tests.firmware.gcode.conftest import require_chip

    require_chip()
    from nnik import pipeline
    from nnik.job.open_loop import run_job

    run, _, opts = machines[machine]
    pipeline.export(run)  # the pick's C, as `nnik run` leaves it
    res = run_job(run, REAL / name, opts=opts)
    c = res["chip"]
    assert c["steps_equal"] and c["replies_equal"] and c["tool_equal"] and c["selftest_pass"], c
    assert res["clamped"] == 0 and c["flash_bytes"] <= 32256 and c["ram_bytes"] <= 2048 - 256
