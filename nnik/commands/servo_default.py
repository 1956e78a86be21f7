"""The default controller of `nnik run` on a dc_servo xy_table (issue 29 item 6): the lowest RMS
contour error on the scenario's reference job ON THE IDENTIFIED PLANT, i.e. what nnik knows of the
machine before it ships (the identified speed models with their Coulomb friction, the closed loop of
nnik.implementations.servo.model_loop.simulate_model), not the scenario's true plant, which a real
rig does not give. Every controller is scored the same way: its integer model from a reset (a
neural one from its pretrained weights, learning as it runs) on the reference job; the contour
error is the one tuning minimises (nnik.implementations.servo.measure.score_run: the carriage's
distance to the reference path's pieces within +-0.5 s of each tick, um). Not the distance to the
whole path (nnik.job.servo_measure, the report's tables): a carriage that never moves sits on the
path's start and would score 0 there, and one that lags along the path is not seen. That distance
is kept beside it (path_rms_um) for the report.

A neural controller whose run diverged there (weight clamps over 1 % of its updates,
nnik.job.servo_loop.learning_figures) is never the default. Ties go to the earlier kind in KINDS
(the baselines first). [controller] kind other than "auto" ships that kind whatever the scores.
"""

from __future__ import annotations

import numpy as np


def identified_scores(cfg, models, coulomb_v, controllers: dict, ref) -> dict[str, dict]:
    """kind -> {"rms_um", "max_um", "path_rms_um", "diverged"} of each controller on ref (a
    nnik.job.reference Reference) closed loop around the identified models."""
    from nnik.implementations.servo.measure import score_run
    from nnik.implementations.servo.model_loop import simulate_model
    from nnik.job.servo_loop import learning_figures
    from nnik.job.servo_measure import path_distance

    out = {}
    for kind, ctl in controllers.items():
        pos, duty = simulate_model(cfg, models, ctl, ref.counts, coulomb_v)
        s = score_run(cfg, ref.counts, pos, duty)
        learning = learning_figures(ctl)
        path = path_distance(pos * cfg.um_per_count, ref.um)
        out[kind] = {"rms_um": s["rms_contour_um"], "max_um": s["max_contour_um"],
                     "path_rms_um": float(np.sqrt(np.mean(path * path))), "diverged": bool(learning and learning["diverged"])}
    return out


def choose(asked: str, scores: dict[str, dict], ref_job: str) -> tuple[str, str]:
    """(the default kind, why, one line): the lowest RMS among the runs that did not diverge
    (asked "auto"), else the asked kind."""
    fit = {k: s for k, s in scores.items() if not s["diverged"]} or scores
    lowest = min(fit, key=lambda k: fit[k]["rms_um"])
    where = f"RMS contour error (tuning's: to the path within +-0.5 s) on {ref_job} on the identified plant"
    if asked != "auto":
        return asked, (f"[controller] kind = {asked!r}; the lowest {where} is {lowest}'s "
                       f"({scores[lowest]['rms_um']:.1f} um, {asked} {scores[asked]['rms_um']:.1f} um)")
    dropped = [k for k in scores if k not in fit]
    return lowest, (f"the lowest {where}: {scores[lowest]['rms_um']:.1f} um"
                    + (f"; diverged there, so not eligible: {', '.join(dropped)}" if dropped else ""))
