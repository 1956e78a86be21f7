"""`nnik run SCENARIO` on a DC-servo xy_table: identify the plant, tune the baselines, pretrain the
neural controllers, run the seed's tests closed loop, compare, write the report.

1. excitation (nnik.dynamics.servo.excite_plan: the seed's square + noise, both axes at once) on
   the scenario's plant, its log -> identify (nnik.dynamics.servo.fit: K and tau per axis);
2. tune pid, pdff and ccc against the identified models (nnik.implementations.servo.tune) on the
   reference job (datasets/jobs/xy_table_reference.gcode), the same trials and seed for each;
3. pretrain nn_axes and nn_vector on the identified models (nnik.job.servo_pretrain) on the seed's
   steps (the shipped step tests) and the reference job, from the [controller] seed;
4. the default controller (nnik.commands.servo_default): the lowest RMS contour error on the
   reference job on the IDENTIFIED plant (what a real rig gives), named with why;
5. every shipped test (TESTS) closed loop with each of the 5 controllers on the scenario's (true)
   plant, in Python and on the simulated Uno when the toolchain is there (every controller's C,
   chip = model tick by tick: duties and the neural weights' checksum, mismatch 0 required);
6. the honest comparison (nnik.job.servo_compare): every controller on the nominal, drifting and
   differing plants on every test, its tables and learning curves in the report;
7. OUTDIR: scenario.toml, servo/identified.toml, servo/gains.json (the baselines' gains, the neural
   params), servo/pretrain.json (the pretraining's log), c/ (the chosen controller's C),
   report/closed_loop.md with one PNG per test, report/compare.md and learning_*.png, job/.
"""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

from nnik.errors import NnikError
from nnik.implementations.servo import BASELINES, KINDS, NEURAL

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"
REFERENCE_JOB = "xy_table_reference.gcode"
TESTS = ("servo_step_x25.gcode", "servo_step_y20.gcode", "servo_step_sequence.gcode", "servo_circle.gcode",
         REFERENCE_JOB)
EXCITE_S = 20.0
PRETRAIN_FILE = "servo/pretrain.json"


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
    from nnik.commands.servo_default import choose, identified_scores
    from nnik.commands.servo_report_md import write_report
    from nnik.implementations.servo import make
    from nnik.implementations.servo.tune import tune
    from nnik.job.closed_loop import ClosedLoopJob
    from nnik.job.parse import JobRequest
    from nnik.job.reference import job_reference
    from nnik.job.servo_dir import GAINS_FILE, IDENTIFIED_FILE, SCENARIO_FILE, ServoDir

    t0 = time.perf_counter()
    ctl = scn.controller  # [controller] with its defaults
    seed, trials, limits = ctl["seed"], ctl["tune_trials"], ctl
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
    coulomb = tuple(f.coulomb_v for f in fits)
    gains = {}
    for kind in BASELINES:
        gains[kind] = tune(kind, scn.servo, models, ref.counts, trials, seed, limits["max_overshoot_um"],
                           limits["max_saturated_fraction"], coulomb)
        say(f"tuned {kind} on {REFERENCE_JOB} against the identified model ({trials} trials): "
            + ", ".join(f"{k} {v:.4g}" for k, v in gains[kind].items()))
    pretrained = _pretrain(scn, models, coulomb, seed, say)
    gains.update({k: p for k, (p, _) in pretrained.items()})
    scores = identified_scores(scn.servo, models, coulomb, {k: make(k, gains[k], scn.servo) for k in KINDS}, ref)
    best, why = choose(ctl["kind"], scores, REFERENCE_JOB)
    say(f"default controller: {best} ({why}; " + ", ".join(f"{k} {s['rms_um']:.1f}" for k, s in scores.items())
        + " um)")
    model = ServoDir(out, scn, best, gains)
    results = {}
    for job in TESTS:
        req = JobRequest(JOBS / job, scn)
        results[job] = {k: ClosedLoopJob(k, False, tag=k).run(model, req) for k in KINDS}
    (out / PRETRAIN_FILE).write_text(json.dumps({k: lg for k, (_, lg) in pretrained.items()}, indent=1) + "\n")
    data = {"chosen": best, "gains": gains, "reference_job": REFERENCE_JOB, "trials": trials, "seed": seed,
            "default": {"why": why, "identified_plant": scores, "coulomb_v": list(coulomb)}}
    (out / GAINS_FILE).write_text(json.dumps(data, indent=2) + "\n")  # last: a model dir only once it is whole
    from nnik.implementations.servo.emit_c import write_controller_c

    write_controller_c(model.controller(best), out / "c", f"nnik run {scn.source}: {best}, the default controller")
    say(f"C of {best}: {out / 'c'}/ (nnik_servo_config.h with its gains, the controllers' sources)")
    chip = _chip(out, scn, model, use_chip, say)
    from nnik.job.servo_compare import compare

    cmp = compare(scn, gains, out / "report", say, jobs=[JOBS / j for j in TESTS], models=models)
    md = write_report(out, scn, fits, gains, best, results, chip,
                      {"why": why, "scores": scores, "pretrain": {k: lg for k, (_, lg) in pretrained.items()},
                       "compare": cmp})
    say(f"report: {md}")
    return {"chosen": best, "results": results, "chip": chip, "seconds": time.perf_counter() - t0}


def _pretrain(scn, models, coulomb, seed: int, say) -> dict:
    """kind -> (params, log) of each neural controller (nnik.job.servo_pretrain: the seed's steps and
    the reference job on the identified models), and the impulse Jacobians beside the seed's."""
    from nnik.job.servo_pretrain import pretrain_all

    params, logs = pretrain_all(scn, models, coulomb, seed, say=say)
    jac = next(iter(logs.values()))["jacobian"]
    say(f"impulse Jacobians on the identified model (12 V, 40 mm): X {jac[0]:.4f}, Y {jac[1]:.4f} (the seed's rig: "
        "X 1.0103, Y 0.6047)")
    return {k: (params[k], logs[k]) for k in params}


def _chip(out: Path, scn, model, use_chip: bool | None, say) -> dict:
    """Every controller's C on the simulated Uno, every test closed loop, chip = model tick by tick
    (the chosen controller last, so OUTDIR/job/TEST.json are its figures)."""
    from nnik.job.closed_loop import ClosedLoopJob
    from nnik.job.parse import JobRequest
    from nnik.job.servo_loop import chip_missing

    why = chip_missing()
    if use_chip is False or why:
        say(f"chip: not run ({'not asked' if use_chip is False else why})")
        return {"not_run": "not asked" if use_chip is False else why}
    res = {}
    for kind in sorted(KINDS, key=lambda k: k == model.chosen):
        for job in TESTS:
            r = ClosedLoopJob(kind, True).run(model, JobRequest(JOBS / job, scn))["chip"]
            res.setdefault(kind, {})[job] = r
            if r["mismatches"]:
                raise NnikError(f"the chip's {kind} duty differs from the model's at {r['mismatches']} ticks on {job}")
        worst = max(res[kind].values(), key=lambda r: r["tick_cycles_max"])
        say(f"chip {kind}: mismatch 0 on every test; controller cycles per tick: max "
            f"{max(r['controller_cycles_max'] for r in res[kind].values())}; the tick with the encoder interrupts: "
            f"max {worst['tick_cycles_max']} cycles ({worst['cpu_pct_max']:.1f} % CPU)")
    return res
