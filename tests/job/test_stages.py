"""The job as one-way stages (nnik/job/): each stage imports only the stages before it, none of
them opens the model directory (it is read once, into a ModelDir), and the figures the stages
write are the ones the firmware's model gives when its parts are called directly, in the order
`nnik job` always ran them (the expectation below), so the pipeline changes nothing.

The models are trained in this session (tests/conftest.py: galvo_run, corexy_run, on another
seed under NNIK_TEST_SEED_OFFSET): nothing here leans on one training's figures."""

from __future__ import annotations

import ast
import json
import os
import sys
from pathlib import Path

import pytest

from nnik.firmware.config import default_machine
from nnik.firmware.gcode.compensation import job_dynamics
from nnik.firmware.gcode.contour import contour_report
from nnik.firmware.gcode.tool_sync import summary, switches
from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
from nnik.firmware.gcode.motion import interpret, plan_steps
from nnik.firmware.gcode.reader import sendable
from nnik.firmware.gcode.steps import model_events
from nnik.firmware.ik_oracle import ik_oracle, load_scenario_of
from nnik.firmware.model_dir import ModelDir
from nnik.job.measure import motion_report, tool_report
from nnik.job.open_loop import OpenLoopJob, run_job
from nnik.job.parse import JobRequest

JOB_PKG = Path(__file__).resolve().parents[2] / "nnik" / "job"
STAGES = ("parse", "plan", "shape", "sample", "cosim", "measure", "report")
JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"


def _job_imports(path: Path) -> set[str]:
    """The nnik.job modules a module imports (lazy imports too)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.module == "nnik.job":
                out |= {a.name for a in node.names}
            elif node.module.startswith("nnik.job."):
                out.add(node.module.split(".")[2])
        elif isinstance(node, ast.Import):
            out |= {a.name.split(".")[2] for a in node.names if a.name.startswith("nnik.job.")}
    return out


def test_each_stage_imports_only_the_stages_before_it():
    kinds = {p.stem for p in JOB_PKG.glob("*.py")} - set(STAGES) - {"__init__"}
    assert kinds >= {"kind", "open_loop"}, kinds
    for k, stage in enumerate(STAGES):
        got = _job_imports(JOB_PKG / f"{stage}.py")
        assert got <= set(STAGES[:k]), f"{stage} imports {sorted(got - set(STAGES[:k]))}, not before it"


_OPENED: list = []  # [OUTDIR, [files opened under it]] while a test watches


def _audit(event, args):
    if event == "open" and _OPENED and isinstance(args[0], (str, bytes, os.PathLike)):
        p = os.path.abspath(os.fsdecode(args[0]))
        root, job = _OPENED[0], os.path.join(_OPENED[0], "job")
        if p.startswith(root + os.sep) and p != job and not p.startswith(job + os.sep):
            _OPENED[1].append(p)


sys.addaudithook(_audit)


@pytest.mark.parametrize("shaper", [None, "auto"])
def test_no_stage_opens_the_model_directory(corexy_run, shaper):
    """Once its ModelDir holds the scenario and the IK, a job (with the belts' every method on
    the tip) opens nothing in OUTDIR but its own OUTDIR/job/."""
    model = ModelDir.load(corexy_run)
    model.scenario, model.ik  # noqa: B018  (read now, before the watch)
    req = JobRequest(JOBS / "l_path.gcode", model.scenario, shaper=shaper)
    _OPENED[:] = [str(Path(corexy_run).resolve()), []]
    try:
        res = OpenLoopJob(use_chip=False).run(model, req)
    finally:
        opened = _OPENED[1]
        _OPENED.clear()
    assert res["dynamics"]["methods"]  # the compensations ran
    assert opened == [], opened


def _expected(outdir: Path, job: Path, shaper: str | None = None, precompensate: bool = False) -> dict:
    """`nnik job --no-chip` as the firmware's parts give it, called one by one (the IK and the
    scenario read from OUTDIR here, independently of ModelDir)."""
    scn, ik = load_scenario_of(outdir), ik_oracle(outdir)
    asked = "precompensated" if precompensate else (shaper or (scn.motion or {}).get("shaper", "none"))
    cfg = default_machine(scn, "none" if asked in ("auto", "precompensated") else asked)
    prep = prepare(read_job(job), cfg, JobOptions(), str(job))
    cfg, lines = prep.cfg, [sendable(ln).decode("latin-1") for ln in prep.lines]
    dyn = None
    if scn.dynamics:
        (outdir / "job").mkdir(exist_ok=True)
        cfg, lines, dyn, _ = job_dynamics(scn, cfg, lines, ik, asked, precompensate, str(job), outdir / "job", job.stem)
    plan = interpret(lines, cfg)
    assert set(plan.replies) == {"ok"}
    seg = plan_steps(plan, cfg, ik)
    res = {"scenario": scn.name, "job": job.name, "unit": scn.unit, "gcode": prep.summary,
           "machine": {"origin_um": list(cfg.origin_um), "seg_um": cfg.seg_um, "tick_hz": cfg.tick_hz,
                       "sample_hz": cfg.sample_hz, "shaper": cfg.shaper, "tool": cfg.tool,
                       "tool_defines": cfg.defines()},
           "tool": {**tool_report(seg, cfg), "switches": summary(switches(plan, seg, cfg))}, "motion": motion_report(seg, cfg, scn.dynamics),
           **contour_report(scn, cfg, plan, seg, model_events(seg))}
    del res["plot"]
    if dyn is not None:
        res["dynamics"] = dyn
        res["tip"] = {k: dyn["methods"][dyn["chosen"]][k] for k in ("contour_um", "dynamics_um", "ringing_um",
                                                                    "ringing_floor_um")}
    return {**res, "chip": {"not_run": "not asked"}, "png": str(outdir / "job" / f"{job.stem}.png")}


@pytest.mark.parametrize("run, job, kw", [
    ("galvo_run", "l_path", {}),
    ("galvo_run", "circle", {}),
    ("corexy_run", "star", {}),
    ("corexy_run", "l_path", {"shaper": "zvd"}),
    ("corexy_run", "l_path", {"shaper": "auto"}),  # auto's pick is a shaper the parsed machine did not have
    ("corexy_run", "l_path", {"precompensate": True}),
])
def test_the_stages_write_the_firmware_models_figures(request, run, job, kw):
    """The JSON the stages write, byte for byte, is the one the firmware's parts give (keys and
    their order included): a stage that hands on the wrong machine, lines or plan, or drops,
    renames or reorders a figure, fails here."""
    outdir = request.getfixturevalue(run)
    path = JOBS / f"{job}.gcode"
    want = json.dumps(_expected(outdir, path, **kw), indent=2) + "\n"
    res = run_job(outdir, path, use_chip=False, **kw)
    assert json.dumps(res, indent=2) + "\n" == want
    assert (outdir / "job" / f"{job}.json").read_text() == want
