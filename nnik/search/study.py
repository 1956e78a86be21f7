"""`nnik search`: a multi-objective design-space search over every implementation family.

Optuna's seeded NSGA-II sampler proposes a family and its knobs (:mod:`nnik.search.space`); a
trial fits it and scores three objectives, all minimised: pre-rounding max error on the problem's
check set (a subsample first, the full set once it meets max_error), estimated cycles on the
[target] chip, and the model's estimated flash bytes. [target]'s max_error, max_cycles and
max_flash_bytes are the sampler's constraints. A configuration that cannot be built is a pruned
trial, its reason recorded. The study lives in OUTDIR/search.journal or a database
(:mod:`nnik.search.storage`); rerunning continues it up to --trials finished trials.

After the search the Pareto front is refitted; each family's cheapest point on the feasible
front gets the full checks of :mod:`nnik.selection` (host, both simulated chips, portable paths),
every other front point that meets max_error (up to a cap) the host and the chips' fast path
(:mod:`nnik.search.front`); the pick is chosen and exported exactly as :mod:`nnik.selection`
does; metrics["selection"] (the refitted front as its "ladder") and metrics["search"] (the front's
rows with what was measured) are written. Only the CLI imports this module.
"""

from __future__ import annotations

import json
import os
import socket
import time
from pathlib import Path

from nnik import pipeline

from nnik.files import pick_state
from nnik import selection as sel
from nnik.errors import NnikError
from nnik.implementations import FAMILIES
from nnik.implementations.accuracy import accuracy
from nnik.implementations.base import TARGETS
from nnik.search.front import config_key, verify_front
from nnik.implementations.mlp.family import fast_problem
from nnik.search.space import SEARCHED, params_of, suggest
from nnik.search.storage import open_storage, open_study, storage_kind

SEED = 20261123
POPULATION = 20
MUTATION = 0.25  # per parameter (Optuna's default is 1 / number of parameters, about 0.05 here)
DIRECTIONS = ("minimize", "minimize", "minimize")
WORKER = f"{socket.gethostname()}:{os.getpid()}"  # which process ran a trial (recorded with it; worker_id)
MAX_REFIT = 40  # front points refitted for the report's picture (cheapest on the chip first)


def study_name(scn) -> str:
    return f"nnik-{scn.name}"


# ---- one trial ------------------------------------------------------------------------------------
def constraint_values(attrs: dict, target: dict) -> dict[str, float]:
    """The constraints from [target], each <= 0 where a trial meets it: max_error (on the claimed
    max of a measured machine, its reference's error included, else pre_max), and max_cycles /
    max_flash_bytes if set (a configuration that could not be built meets none)."""
    lim = {"max_error": ("claimed_max" if "claimed_max" in attrs else "pre_max", target["max_error"])}
    lim.update({t: (k, target[t]) for k, t in (("cycles", "max_cycles"), ("flash_bytes", "max_flash_bytes"))
                if target.get(t)})
    if "pre_max" not in attrs:
        return {name: 1.0 for name in lim}
    return {name: float(attrs[k]) - float(v) for name, (k, v) in lim.items()}


def feasible(attrs: dict, target: dict) -> bool:
    return all(v <= 0 for v in constraint_values(attrs, target).values())


class Objective:
    """Fit one proposal and score it; identical configurations are fitted once per study."""

    def __init__(self, problem, target: dict, families: list[str], seen: dict):
        self.problem, self.target, self.families, self.seen = problem, target, families, seen
        self.quick = sel._quick_points(problem)

    def measure(self, fam: str, cfg: dict) -> dict:
        try:
            impl = FAMILIES[fam].fit(self.problem, cfg)
            acc = accuracy(impl, self.quick)
            if acc.get("claimed_max", acc["pre_max"]) <= self.target["max_error"]:
                acc = accuracy(impl)
            est = {t: impl.estimate(t) for t in TARGETS}
        except NnikError as exc:
            return {"error": str(exc)}
        chip = self.target["chip"]
        claim = {"claimed_max": acc["claimed_max"]} if "claimed_max" in acc else {}
        return {"pre_max": acc["pre_max"], **claim, "check_points": acc["points"], "cycles": float(est[chip]["cycles"]),
                "flash_bytes": int(est[chip]["flash_bytes"]), "describe": impl.describe(),
                "estimate": {t: {k: est[t][k] for k in ("cycles", "flash_bytes", "validated") if k in est[t]}
                             for t in TARGETS}}

    def __call__(self, trial):
        import optuna

        fam, cfg = suggest(trial, self.problem, self.families)
        key = json.dumps([fam, cfg], sort_keys=True)
        res = self.seen.get(key)
        if res is None:
            res = self.seen[key] = self.measure(fam, cfg)
        trial.set_user_attr("worker", WORKER)
        trial.set_user_attr("family", fam)
        trial.set_user_attr("config", cfg)
        for k, v in res.items():
            trial.set_user_attr(k, v)
        for k, v in constraint_values(res, self.target).items():  # what NSGA-II ranks feasibility by
            trial.set_constraint(k, v)
        if "error" in res:
            raise optuna.TrialPruned(res["error"])
        return res.get("claimed_max", res["pre_max"]), res["cycles"], res["flash_bytes"]


def _seen(study) -> dict:
    """Results of the study's finished trials, keyed by configuration."""
    out = {}
    for t in _finished(study):
        a = t.user_attrs
        if "family" in a and ("pre_max" in a or "error" in a):
            out[json.dumps([a["family"], a["config"]], sort_keys=True)] = {
                k: v for k, v in a.items() if k not in ("family", "config", "worker")}
    return out


def _finished(study) -> list:
    from optuna.trial import TrialState

    return study.get_trials(deepcopy=False, states=(TrialState.COMPLETE, TrialState.PRUNED, TrialState.FAIL))


def best_per_family(study, target: dict) -> dict[str, str]:
    """family -> its cheapest feasible point so far (cycles), else its most accurate."""
    out = {}
    comp = [t for t in _finished(study) if "pre_max" in t.user_attrs]
    for fam in dict.fromkeys(t.user_attrs["family"] for t in comp):
        ts = [t.user_attrs for t in comp if t.user_attrs["family"] == fam]
        ok = [a for a in ts if feasible(a, target)]
        if ok:
            a = min(ok, key=lambda a: (a["cycles"], a["flash_bytes"]))
            out[fam] = f"{a['cycles']:.0f}c"
        else:
            out[fam] = f"err {min(a.get('claimed_max', a['pre_max']) for a in ts):.3g}"
    return out


# ---- workers --------------------------------------------------------------------------------------
def run_worker(outdir: str, url: str | None, name: str, n_total: int, families: list[str], worker: int = 0,
               progress: bool = False) -> None:
    """Run trials against the shared study until it holds n_total finished trials."""
    import optuna
    from optuna.study import MaxTrialsCallback
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    out = Path(outdir)
    problem = fast_problem(pipeline.problem_for(out))
    target = problem.scn.target
    storage = open_storage(url, out)
    scn = problem.scn
    done = len(_finished(open_study(storage, name, scn.fingerprint, scn.name, list(DIRECTIONS))))
    if done >= n_total:
        return
    # the seed moves on with the study, so a resumed search does not repeat its first proposals
    # constrained domination puts every feasible point before any infeasible one, so a family whose
    # first points miss the target would die out: a high mutation rate keeps proposing it
    sampler = optuna.samplers.NSGAIISampler(population_size=POPULATION, mutation_prob=MUTATION,
                                            seed=SEED + 7919 * worker + done)
    study = open_study(storage, name, scn.fingerprint, scn.name, list(DIRECTIONS), sampler=sampler)
    objective = Objective(problem, target, families, _seen(study))
    callbacks = [MaxTrialsCallback(n_total, states=(TrialState.COMPLETE, TrialState.PRUNED, TrialState.FAIL))]
    bar = None
    if progress:
        from nnik.progress import bar as progress_bar

        bar = progress_bar(total=n_total, initial=done, desc="search", unit="trial", leave=False)

        def show(study_, _trial):
            bar.n = min(n_total, len(_finished(study_)))
            bar.set_postfix_str(", ".join(f"{f} {v}" for f, v in best_per_family(study_, target).items()))
            bar.refresh()

        callbacks.append(show)
    try:
        study.optimize(objective, n_trials=n_total - done, callbacks=callbacks, gc_after_trial=False)
    except Exception as exc:  # a full disk under the journal: optuna hides it behind its own error
        from nnik.files.os_errors import os_error_behind

        raise (os_error_behind(exc) or exc) from None
    finally:
        if bar:
            bar.close()


def _spawned(outdir, url, name, n_total, families, worker):
    from nnik.files.outdir import release_locks

    try:
        run_worker(outdir, url, name, n_total, families, worker)
    except NnikError as exc:
        print(f"nnik: error: search worker {worker}: {exc}", flush=True)
        raise SystemExit(2) from None
    finally:
        release_locks()


def searched_families(families: list[str] | None) -> list[str]:
    """The families a search samples (default: every family with knobs in the space); one line
    for a family that is unknown or has no knobs there."""
    fams = list(families or [f for f in FAMILIES if f in SEARCHED])
    bad = [f for f in fams if f not in FAMILIES]
    if bad:
        raise NnikError(f"unknown implementation family {bad[0]!r} (known: {', '.join(FAMILIES)})")
    bad = [f for f in fams if f not in SEARCHED]
    if bad:
        raise NnikError(f"family {bad[0]!r} has no knobs in the search space (nnik/search/space.py); "
                        f"searched: {', '.join(SEARCHED)}")
    return fams


def search(outdir: Path, trials: int, url: str | None = None, name: str | None = None, jobs: int = 1,
           families: list[str] | None = None, progress: bool = True, worker_only: bool = False,
           warm_start: bool = True, bests: list[tuple[str, dict]] | None = None) -> dict:
    """Run (or continue) the search to ``trials`` finished trials, then verify and pick (not with
    ``worker_only``: a worker on one of several machines only runs trials). ``bests``: each
    family's ladder best, just fitted by the caller, for the warm start (see :func:`warm`)."""
    import multiprocessing as mp

    if trials < 1 or jobs < 1:
        raise NnikError("--trials and --jobs must be at least 1")
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    fams = searched_families(families)
    scn = pipeline.load_pair(outdir)[0].scenario
    name = name or study_name(scn)
    storage = open_storage(url, outdir)  # bad URL, unreachable server, other scenario: fail before any work
    study = open_study(storage, name, scn.fingerprint, scn.name, list(DIRECTIONS))
    before = {t.number for t in _finished(study)}
    if warm_start and not study.get_trials(deepcopy=False):
        warm(study, outdir, fams, bests)
    t0 = time.perf_counter()
    procs = []
    if jobs > 1:
        ctx = mp.get_context("spawn")
        procs = [ctx.Process(target=_spawned, args=(str(outdir), url, name, trials, fams, w)) for w in range(1, jobs)]
        for p in procs:
            p.start()
    try:
        run_worker(str(outdir), url, name, trials, fams, 0, progress)
    finally:
        for p in procs:
            p.join()
    seconds = time.perf_counter() - t0
    study = open_study(storage, name, scn.fingerprint, scn.name, list(DIRECTIONS))
    info = {"seconds": seconds, **trial_counts(study, before, {WORKER} | {worker_id(p.pid) for p in procs}, trials),
            "jobs": jobs, "families": fams}
    info["trials_per_min"] = 60.0 * info["trials_run"] / seconds if info["trials_run"] else None
    if worker_only:
        return {"search": {"study": name, "storage": storage_kind(url), **info}}
    return finish(outdir, study, url, info, progress)


def worker_id(pid: int) -> str:
    """What a trial records as the process that ran it (see Objective)."""
    return f"{socket.gethostname()}:{pid}"


def trial_counts(study, before: set[int], mine: set[str], target: int) -> dict:
    """This command's share of a study other processes may share: the trials it ran (its own
    process and its --jobs workers), the trials every process added meanwhile, and what the study
    holds now."""
    new = [t for t in _finished(study) if t.number not in before]
    ran = sum(t.user_attrs.get("worker") in mine for t in new)
    return {"trials_run": ran, "trials_added": len(new), "study_trials": len(before) + len(new),
            "trials_target": target}


def ladder_bests(problem, families: list[str]) -> list[tuple[str, dict]]:
    """Each family's best on the ladder for the problem's [target] (what `nnik run` picks from):
    the cheapest configuration that meets max_error, else the most accurate (pipeline.fit_bests)."""
    _, bests = pipeline.fit_bests(problem, problem.scn.target, families)
    return [(fam, c.config) for fam, c in bests.items()]


def warm(study, outdir: Path, families: list[str], bests: list[tuple[str, dict]] | None = None) -> int:
    """Queue each family's ladder best first, then every family's ladder, as the new study's first
    trials: even a search of a few trials evaluates what `nnik run` would pick from, so it never
    returns worse than the ladder, and can only improve on it; returns how many were queued.
    The bests are ``bests`` (a ladder just fitted), else the ones a finished `nnik run` recorded
    in OUTDIR for these very inputs and [target] (pipeline.stored_bests), else the ladder is fitted."""
    from itertools import chain, zip_longest

    problem = pipeline.problem_for(outdir)
    if bests is None:
        bests = pipeline.stored_bests(outdir, problem.scn.target, families)
    if bests is None:
        bests = ladder_bests(problem, families)
    queued = [params_of(fam, cfg) for fam, cfg in bests if fam in families]
    ladders = [[params_of(fam, cfg) for cfg in FAMILIES[fam].ladder(problem)] for fam in families]
    n = 0
    # the bests, then the families in turn: a short search sees each
    for p in chain(queued, chain.from_iterable(zip_longest(*ladders))):
        if p is not None:
            study.enqueue_trial(p, skip_if_exists=True)  # a best is also on its ladder: queued once
            n += 1
    return n


# ---- the front, verified ----------------------------------------------------------------------------
def front_trials(study, target: dict, feasible_only: bool = False) -> list:
    """The Pareto-optimal completed trials (error, cycles, flash), one per configuration, cheapest on
    the chip first: over every trial (the picture of the trade-off), or over those that meet
    [target] (where the pick comes from)."""
    from optuna.trial import TrialState

    pool = [t for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)) if t.values]
    if feasible_only:
        pool = [t for t in pool if feasible(t.user_attrs, target)]
    front = [t for t in pool if not any(_dominates(o.values, t.values) for o in pool)]
    uniq = {}
    for t in sorted(front, key=lambda t: (t.values[1], t.values[2], t.values[0], t.number)):
        uniq.setdefault(config_key(t.user_attrs["family"], t.user_attrs["config"]), t)
    return list(uniq.values())


def _dominates(a, b) -> bool:
    return all(x <= y for x, y in zip(a, b)) and any(x < y for x, y in zip(a, b))


def front_rows(front: list, target: dict) -> list[dict]:
    """The rows of metrics["search"]["front"] for the trials of a front (:func:`front_trials`)."""
    return [{"trial": t.number, "family": t.user_attrs["family"], "config": t.user_attrs["config"],
             "describe": t.user_attrs.get("describe"), "pre_max": t.user_attrs.get("pre_max", t.values[0]),
             **({"claimed_max": t.values[0]} if "claimed_max" in t.user_attrs else {}), "cycles": t.values[1],
             "flash_bytes": int(t.values[2]), "meets_target": feasible(t.user_attrs, target)}
            for t in front]


def show(outdir: Path, url: str | None = None, name: str | None = None) -> dict:
    """The study's state and front, without running anything."""
    import optuna
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(optuna.logging.WARNING)

    scn = pipeline.load_pair(outdir)[0].scenario
    name = name or study_name(scn)
    study = open_study(open_storage(url, outdir), name, scn.fingerprint, scn.name, list(DIRECTIONS), create=False)
    states = {s.name.lower(): len(study.get_trials(deepcopy=False, states=(s,))) for s in TrialState}
    return {"study": name, "storage": storage_kind(url), "trials": states, "target": scn.target,
            "front": front_rows(front_trials(study, scn.target), scn.target)}


def _candidate(problem, fam: str, cfg: dict) -> sel.Candidate:
    c = sel.Candidate(fam, cfg)
    try:
        c.impl = FAMILIES[fam].fit(problem, cfg)
        c.acc = accuracy(c.impl)
        c.est = {t: c.impl.estimate(t) for t in TARGETS}
    except NnikError as exc:
        c.impl, c.skipped = None, str(exc)
    return c


def finish(outdir: Path, study, url: str | None, info: dict, progress: bool = True) -> dict:
    """Refit the front, verify each family's cheapest point on it (full checks) and the rest of the
    front that meets max_error (fast path), pick, export, write metrics."""
    from optuna.trial import TrialState
    from nnik.progress import bar

    problem = fast_problem(pipeline.problem_for(outdir))
    target = problem.scn.target
    pick_state.invalidate(outdir)  # c/alt/ and the pick are about to change
    # the pick comes from the front of the trials that meet [target]; the picture shows the whole front
    ok_front = front_trials(study, target, feasible_only=True)
    front = front_trials(study, target)
    comp = [t for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)) if t.values]
    chosen = list({t.number: t for t in ok_front[:MAX_REFIT] + front[:MAX_REFIT]}.values())
    # a family absent from both is still shown: its most accurate trial
    fams = {t.user_attrs["family"] for t in chosen}
    for fam in dict.fromkeys(t.user_attrs["family"] for t in comp):
        if fam not in fams:
            chosen.append(min((t for t in comp if t.user_attrs["family"] == fam), key=lambda t: t.values[0]))
    cands = [_candidate(problem, t.user_attrs["family"], t.user_attrs["config"])
             for t in bar(chosen, desc="refit the front", unit="config", disable=not progress, leave=False)]
    bests = sel.family_bests([c for c in cands if c.impl is not None], target)
    # only the points that meet max_error are verified: a large MLP that misses takes minutes on gpsim
    pipeline.verify_bests(outdir, bests, progress, only_meeting=target["max_error"])
    rows = front_rows(front, target)
    by_key = {config_key(c.family, c.config): c for c in cands}
    c_dir = outdir / pipeline.C_DIR
    verify_info = verify_front(outdir, rows, by_key, bests, target, c_dir / sel.ALT_DIR, progress)
    for c in bests.values():
        if not c.checks:  # shown with its estimate only
            why = {"not_run": f"misses max_error {target['max_error']:g}: not verified"}
            c.checks = {k: dict(why) for k in ("host", *TARGETS, *(f"{t}_portable" for t in TARGETS))}
    states = {s.name.lower(): len(study.get_trials(deepcopy=False, states=(s,))) for s in TrialState}
    search_section = {"study": study.study_name, "storage": storage_kind(url), "trials": states, **info,
                      "feasible_front": len(ok_front), "front": rows, "front_verified": verify_info,
                      "front_families": sorted({t.user_attrs["family"] for t in front})}

    def with_picked(pick) -> dict:
        picked = None if pick is None else (pick.family, pick.impl.source_hash())
        for r in rows:
            r["picked"] = (r["family"], r.get("model_hash")) == picked
        return {"search": search_section}

    _, asked = pipeline.resolve_target(problem)
    section = pipeline.conclude(outdir, problem, cands, bests, target, asked, source="search", extra=with_picked)
    return {"selection": section, "search": search_section}
