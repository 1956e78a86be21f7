"""Tune a controller against the identified model: optuna's TPE sampler, seeded, a fixed number of
trials and no clock (same seed, same trials -> same gains), the same objective and budget for every
kind.

Each trial simulates the integer controller around the identified speed models (model_loop.py) on
the caller's reference (counts per tick) and scores it (measure.py):

    objective = RMS contour error (um)                          when the limits hold
              = LIMIT_PENALTY + RMS contour error * (1 + excess)  when they do not

where excess is the summed relative excess of the overshoot over max_overshoot_um, of the final
error (the carriage at the reference's last tick: the job must end where it ends) over the same
max_overshoot_um, and of the saturated share of ticks over max_saturated_fraction: any trial within the limits beats every trial
outside them, and among those outside, the smaller excess wins. The first trials
are pole placements at 1, 2 and 4 / tau (space.start_points); the sampler is multivariate TPE.
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.servo import KINDS, NEURAL, make
from nnik.implementations.servo.measure import score_run
from nnik.implementations.servo.model_loop import simulate_model
from nnik.implementations.servo.space import start_points, suggest

LIMIT_PENALTY = 1e6


def evaluate(kind: str, gains: dict, cfg, models, ref_counts, max_overshoot_um: float = 25.0,
             max_saturated_fraction: float = 0.05, coulomb_v=(0.0, 0.0)) -> dict:
    """The run's figures and its objective for one set of gains."""
    pos, duty = simulate_model(cfg, models, make(kind, gains, cfg), ref_counts, coulomb_v)
    s = score_run(cfg, ref_counts, pos, duty)
    excess = (max(0.0, s["overshoot_um"] / max_overshoot_um - 1.0)
              + max(0.0, s["final_error_um"] / max_overshoot_um - 1.0)
              + max(0.0, s["saturated_fraction"] / max_saturated_fraction - 1.0))
    s["within_limits"] = excess == 0.0
    s["objective"] = s["rms_contour_um"] if excess == 0.0 else LIMIT_PENALTY + s["rms_contour_um"] * (1.0 + excess)
    return s


def tune(kind: str, cfg, models, ref_counts, trials: int, seed: int, max_overshoot_um: float = 25.0,
         max_saturated_fraction: float = 0.05, coulomb_v=(0.0, 0.0)) -> dict:
    """The best gains (physical units, exactly what the chip runs) after `trials` trials; coulomb_v:
    the identified Coulomb friction per axis, volts (model_loop.py), 0 for a linear model."""
    import optuna

    if kind in NEURAL:
        raise NnikError(f"{kind} is not tuned: the neural controllers are pretrained and learn online")
    if kind not in KINDS:
        raise NnikError(f"unknown controller kind {kind!r} (known: {', '.join(KINDS)})")
    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    if len(ref) < 2:
        raise NnikError("tuning needs a reference of at least 2 ticks")
    if not (isinstance(trials, int) and trials >= 1):
        raise NnikError(f"tune_trials must be a whole number >= 1, not {trials!r}")
    if not (max_overshoot_um > 0 and max_saturated_fraction > 0):
        raise NnikError("max_overshoot_um and max_saturated_fraction must be positive")
    models = tuple(models)
    coulomb_v = tuple(float(c) for c in coulomb_v)
    if len(coulomb_v) != 2 or not all(c >= 0 for c in coulomb_v):
        raise NnikError(f"coulomb_v must be two non-negative volts, not {coulomb_v!r}")

    def objective(trial) -> float:
        g = suggest(kind, trial, cfg, models)
        s = evaluate(kind, g, cfg, models, ref, max_overshoot_um, max_saturated_fraction, coulomb_v)
        trial.set_user_attr("gains", g)
        return s["objective"]

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    sampler = optuna.samplers.TPESampler(seed=seed, multivariate=True)
    study = optuna.create_study(direction="minimize", sampler=sampler)
    for p in start_points(kind, cfg, models)[:trials]:
        study.enqueue_trial(p)
    study.optimize(objective, n_trials=trials, n_jobs=1, gc_after_trial=False)
    return dict(study.best_trial.user_attrs["gains"])
