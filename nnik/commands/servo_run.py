"""`nnik run SCENARIO` on a DC-servo xy_table: identify the plant, tune the baselines, run the
seed's tests closed loop, write the report.

1. excitation (nnik.dynamics.servo.excite_plan: the seed's square + noise, both axes at once) on
   the scenario's plant, its log -> identify (nnik.dynamics.servo.fit: K and tau per axis);
2. tune pid, pdff and ccc against the identified models (nnik.implementations.servo.tune) on the
   reference job (datasets/jobs/xy_table_reference.gcode), the same trials and seed for each;
3. every shipped test (TESTS) closed loop with each controller on the scenario's (true) plant, in
   Python and on the simulated Uno when the toolchain is there (the chosen controller's C);
4. OUTDIR: scenario.toml, servo/identified.toml, servo/gains.json, c/ (the chosen controller's
   C), report/closed_loop.md with one PNG per test, job/ (each test's figures).
The default controller is the lowest RMS contour error on the reference job, on the true plant.
"""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

from nnik.errors import NnikError

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"
REFERENCE_JOB = "xy_table_reference.gcode"
TESTS = ("servo_step_x25.gcode", "servo_step_y20.gcode", "servo_step_sequence.gcode", "servo_circle.gcode",
         REFERENCE_JOB)
KINDS = ("pid", "pdff", "ccc")
EXCITE_S = 20.0


def identify(scn, seed: int):
    """The seed's excitation on the scenario's plant and the speed models fitted to its log."""
    import numpy as np

    from nnik.dynamics.servo.excite_plan import excite
    from nnik.dynamics.servo.fit import fit_log
    from nnik.dynamics.servo.log_csv import ServoLog
    from nnik.dynamics.servo.servo_error import ServoError

    cfg, ws = scn.servo, scn.workspace
    try:  # a plant nnik cannot excite or fit: one line (ServoError is nnik.dynamics' own)
        ex = excite(cfg, tuple((lo * 1000.0, hi * 1000.0) for lo, hi in (ws.x_mm, ws.y_mm)), EXCITE_S, seed)
        t = np.arange(len(ex.duty)) * cfg.tick_s
        log = ServoLog(t, ex.duty * (cfg.supply_v / cfg.duty_max), ex.counts.astype(float), cfg.tick_s, None)
        return fit_log(log)
    except ServoError as exc:
        raise NnikError(f"identifying the plant: {exc}", scn.source) from None


def run_servo(scn, out: Path, say=print, use_chip: bool | None = None) -> dict:
    from nnik.commands.servo_report_md import write_report
    from nnik.implementations.servo.tune import tune
    from nnik.job.closed_loop import ClosedLoopJob
    from nnik.job.parse import JobRequest
    from nnik.job.reference import job_reference
    from nnik.job.servo_dir import GAINS_FILE, IDENTIFIED_FILE, SCENARIO_FILE, ServoDir

    t0 = time.perf_counter()
    ctl = scn.controller or {}
    seed, trials = int(ctl.get("seed", 1)), int(ctl.get("tune_trials", 60))
    (out / "servo").mkdir(parents=True, exist_ok=True)
    shutil.copyfile(scn.source, out / SCENARIO_FILE)
    fits = identify(scn, seed)
    for f in fits:
        m = f.model
        say(f"identified {f.axis}: K {m.k_counts_s_v:.5g} counts/s/V, tau {m.tau_s:.4g} s (95 % CI "
            f"{m.tau_ci[0]:.4g} – {m.tau_ci[1]:.4g} s)")
    (out / IDENTIFIED_FILE).write_text("".join(f.model.scenario_lines(f.axis) + "\n" for f in fits))
    models = tuple(f.model for f in fits)
    _, ref = job_reference(JobRequest(JOBS / REFERENCE_JOB, scn))
    gains = {}
    for kind in KINDS:
        gains[kind] = tune(kind, scn.servo, models, ref.counts, trials, seed)
        say(f"tuned {kind} on {REFERENCE_JOB} against the identified model ({trials} trials): {gains[kind]}")
    model = ServoDir(out, scn, KINDS[0], gains)
    results = {}
    for job in TESTS:
        req = JobRequest(JOBS / job, scn)
        results[job] = {k: ClosedLoopJob(k, False, tag=k).run(model, req) for k in KINDS}
    best = min(KINDS, key=lambda k: results[REFERENCE_JOB][k]["contour_um"]["rms_um"])
    data = {"chosen": best, "gains": gains, "reference_job": REFERENCE_JOB, "trials": trials, "seed": seed}
    (out / GAINS_FILE).write_text(json.dumps(data, indent=2) + "\n")  # last: a model dir only once it is whole
    say(f"default controller: {best} (the lowest RMS contour error on {REFERENCE_JOB}: "
        f"{results[REFERENCE_JOB][best]['contour_um']['rms_um']:.1f} um)")
    from nnik.implementations.servo.emit_c import write_controller_c

    write_controller_c(model.controller(best), out / "c", f"nnik run {scn.source}: {best}, the default controller")
    say(f"C of {best}: {out / 'c'}/ (nnik_servo_config.h with its gains, the controllers' sources)")
    chip = _chip(out, scn, best, use_chip, say)
    md = write_report(out, scn, fits, gains, best, results, chip)
    say(f"report: {md}")
    return {"chosen": best, "results": results, "chip": chip, "seconds": time.perf_counter() - t0}


def _chip(out: Path, scn, best: str, use_chip: bool | None, say) -> dict:
    """The chosen controller's C on the simulated Uno, every test closed loop, chip = model."""
    from nnik.job.closed_loop import ClosedLoopJob
    from nnik.job.parse import JobRequest
    from nnik.job.servo_dir import ServoDir
    from nnik.job.servo_loop import chip_missing

    why = chip_missing()
    if use_chip is False or why:
        say(f"chip: not run ({'not asked' if use_chip is False else why})")
        return {"not_run": "not asked" if use_chip is False else why}
    model = ServoDir.load(out, scn)
    res = {}
    for job in TESTS:
        r = ClosedLoopJob(best, True).run(model, JobRequest(JOBS / job, scn))["chip"]
        res[job] = r
        say(f"chip {best} on {job}: mismatch {r['mismatches']}, controller cycles per tick: max "
            f"{r['controller_cycles_max']}")
        if r["mismatches"]:
            raise NnikError(f"the chip's duty differs from the model's at {r['mismatches']} ticks on {job}")
    return res
