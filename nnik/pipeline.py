"""One pipeline for every implementation family, in stages that read and write OUTDIR.

``nnik run`` is :func:`run`: scenario -> data (:func:`prepare`: the samples, or a measured
machine's marks and the reference model fitted to them) -> every family fitted over its ladder
through the same interface (:func:`fit_bests`; the MLP's training is its family's fit) -> the MLP
family's own files (model.pt, model.onnx, c/mlp/, :func:`keep_mlp`) -> each family's best verified
on the host and the simulated chips (:func:`verify_bests`) -> the pick, c/NAME.c and c/alt/,
metrics.json's selection and pick.json (:func:`conclude`). ``nnik select`` runs the same stages on
a finished OUTDIR; ``nnik search`` (nnik.search.study) fits its own candidates and then shares
:func:`verify_bests` and :func:`conclude`, and its warm start takes the family bests a finished
ladder recorded (:func:`stored_bests`) instead of fitting the ladder again.

The MLP's own steps (``nnik train``, ``evaluate``, ``export``, ``verify --mlp-pipeline``) live in
nnik.implementations.mlp.outputs and are re-exported here for the commands that run them alone.
"""

from __future__ import annotations

from pathlib import Path

from nnik import selection as sel
from nnik.errors import NnikError
from nnik.files import pick_state
from nnik.files.atomic_write import replacing
from nnik.files.c_hash import dir_hash
from nnik.files.metrics import (C_DIR, DATA_FILE, FIXED_EVAL_FILE, METRICS_FILE, MLP_DIR, MODEL_FILE,  # noqa: F401
                                ONNX_FILE, load_metrics, write_metrics)
from nnik.implementations.mlp.outputs import (TARGET_OPTS, check_data_matches, estimate_row, evaluate,  # noqa: F401
                                              export, load_pair, mlp_flash_bytes, quantize_kernel, target_vectors,
                                              train, verify, verify_target)
from nnik.implementations.mlp.train import TrainedModel  # noqa: F401
from nnik.machine.data import Dataset, build_dataset
from nnik.machine.scenario import Scenario


def default_outdir(scn: Scenario, normalize: bool = True) -> Path:
    return Path("build") / (scn.name if normalize else f"{scn.name}-no-normalize")


def generate(scn: Scenario, outdir: Path) -> Dataset:
    outdir.mkdir(parents=True, exist_ok=True)
    pick_state.invalidate(outdir)  # new data: no pick until select or search finishes again
    ds = build_dataset(scn)
    with replacing(outdir / DATA_FILE) as tmp:  # a kill or a full disk leaves the old file, never half of one
        ds.save(tmp)
    return ds


# ---- the stages ---------------------------------------------------------------------------------
def run(scn: Scenario, outdir: Path, progress: bool = True, on_stage=None, pick: bool = True,
        mlp_verify=("host", "avr", "pic18"), families=None) -> dict:
    """`nnik run`: every stage, every family alike (see the module docstring). ``on_stage(name,
    value)`` hears of each finished stage ("data": the Problem; "fitted": (candidates, family
    bests, the MLP family's trained network); "mlp": the MLP's own C verified on each of
    ``mlp_verify``). With ``pick`` false the run stops before the family bests are verified
    (`nnik run --search` and `nnik search SCENARIO` hand them to the search's warm start).
    ``families``: only these (the mlp among them: its network is model.pt; default all).
    Returns the selection section, or {"problem", "candidates", "bests"} without ``pick``."""
    from nnik.implementations.mlp import family as mlp_family

    say = on_stage or (lambda stage, value: None)
    problem = prepare(scn, outdir, progress)
    say("data", problem)
    target, asked = resolve_target(problem)
    cands, bests = fit_bests(problem, target, families, progress)
    say("fitted", (cands, bests, mlp_family.trained(problem)))
    say("mlp", keep_mlp(problem, outdir, verify_on=mlp_verify))
    if not pick:
        return {"problem": problem, "candidates": cands, "bests": bests}
    verify_bests(outdir, bests, progress)
    return conclude(outdir, problem, cands, bests, target, asked)


def prepare(scn: Scenario, outdir: Path, progress: bool = True):
    """Stage 1, data: data.npz and the Problem every family is fitted to. A measured machine's
    reference model is fitted to its marks here, with the scenario's MLP (its family's training,
    on the marks) among its candidates; the ladder then finds that network already trained."""
    from nnik.implementations.mlp.family import own_config, train_network

    ds = generate(scn, outdir)
    model = None if scn.mechanism.analytic else train_network(scn, ds, own_config(scn), progress)
    return build_problem(scn, ds, model)


def problem_for(outdir: Path):
    """The Problem of a finished OUTDIR (model.pt and data.npz), its trained MLP in the cache."""
    model, ds = load_pair(outdir)
    return build_problem(model.scenario, ds, model)


def build_problem(scn, ds: Dataset, model=None):
    """The Problem of a scenario: for a measured machine with its reference fitted to the marks
    (the trained MLP, if given, a candidate scored on its held-out rows, and kept in the problem's
    cache as the MLP family's fit), and [target] max_error filled in by with_default_target."""
    from nnik.implementations import Problem
    from nnik.implementations.mlp.family import remember_trained

    reference = None
    if not scn.mechanism.analytic:  # measured: the families compile a reference fitted to the marks
        from nnik.machine.reference import reference_for

        mlp = None if model is None else (model.predict, ds.p["test"], model.predict(ds.p["test"]) - ds.q["test"])
        reference = reference_for(scn, mlp)
    scn = with_default_target(scn, reference.error_max if reference is not None else 0.0)
    problem = Problem(scn, ds, unit_um=scn.export["input_unit_um"], reference=reference)
    if model is not None:
        remember_trained(problem, model)
    return problem


DEFAULT_MAX_ERROR = 0.25  # output units: without [target] max_error, max(this, DEFAULT_FLOOR_FACTOR x error floor)
DEFAULT_FLOOR_FACTOR = 1.25  # a measured machine's implementation may add a quarter of its reference's error


def with_default_target(scn, error_floor: float):
    """The scenario with [target] max_error filled in when the TOML does not give it:
    max(DEFAULT_MAX_ERROR, DEFAULT_FLOOR_FACTOR x error floor), the floor being 0 for an exact IK
    and the reference's estimated max error for a measured machine (whose readings may be coarser
    than 0.25 of a unit). ``max_error_source`` says which."""
    import dataclasses

    if "max_error" in (scn.raw.get("target") or {}):
        return dataclasses.replace(scn, target={**scn.target, "max_error_source": "scenario"})
    value = float(f"{max(DEFAULT_MAX_ERROR, DEFAULT_FLOOR_FACTOR * error_floor):.3g}")
    how = (f"default: max({DEFAULT_MAX_ERROR:g}, {DEFAULT_FLOOR_FACTOR:g} x the reference's estimated error "
           f"{error_floor:.3g})" if error_floor else f"default: {DEFAULT_MAX_ERROR:g}")
    return dataclasses.replace(scn, target={**scn.target, "max_error": value, "max_error_source": how})


def resolve_target(problem, overrides: dict | None = None) -> tuple[dict, bool]:
    """The [target] the pick is made for (the scenario's, ``overrides`` from the command line on
    top) and whether max_error was asked for (else it is the default, which a pick may miss).
    The overrides are checked as the scenario's [target] table is, before anything is written."""
    from nnik.machine.params import validate_table
    from nnik.machine.scenario import TARGET

    for key, value in (overrides or {}).items():
        validate_table({key: value}, {key: TARGET[key]}, "the command line", "target")
    target = {**problem.scn.target, **(overrides or {})}
    if target.get("max_error") != problem.scn.target.get("max_error"):
        target["max_error_source"] = "command line"
    asked = "max_error" in (problem.scn.raw.get("target") or {}) or "max_error" in (overrides or {})
    return target, asked


def fit_bests(problem, target: dict, families=None, progress: bool = False):
    """Stage 2: every family's ladder fitted through the same interface (the MLP trains here,
    unless its network is already in the problem's cache) and measured on the check set;
    returns (every candidate, each family's best for ``target``)."""
    from nnik.progress import bar

    cands = sel.fit_ladder(problem, families, progress=(lambda **k: bar(leave=False, **k)) if progress else None,
                           max_error=target["max_error"])
    return cands, sel.family_bests(cands, target)


def keep_mlp(problem, outdir: Path, verify_on=("host", "avr", "pic18")) -> dict:
    """The MLP family's own files (nnik.implementations.mlp.outputs.keep): model.pt, model.onnx,
    its accuracy; then c/mlp/ and the float IK verified on ``verify_on``. Returns target ->
    verification result."""
    from nnik.implementations.mlp import outputs

    outputs.keep(problem, outdir)
    return {t: verify(outdir, t) for t in verify_on}


def verify_bests(outdir: Path, bests: dict, progress: bool = False, only_meeting: float | None = None) -> None:
    """Stage 3: each family's best (or, with ``only_meeting``, those that meet that max_error)
    verified on the host and both simulated chips, from its C in c/alt/<family>/."""
    from nnik.progress import bar

    todo = [c for c in bests.values() if only_meeting is None or c.meets(only_meeting)]
    for c in bar(todo, desc="verify family bests", unit="family", disable=not progress, leave=False):
        sel.verify_candidate(c, outdir / C_DIR / sel.ALT_DIR / c.family, (outdir / "targets" / "families").resolve())


def conclude(outdir: Path, problem, cands: list, bests: dict, target: dict, asked: bool = True,
             source: str = "ladder", extra=None) -> dict:
    """Stage 4: pick among the verified family bests, write c/NAME.{c,h} and c/alt/ (only
    verified C), metrics.json's selection (plus ``extra(pick)``'s sections) and, last, pick.json.
    Raises the reason when nothing can be picked (every family's best is then in c/alt/)."""
    pick = sel.choose(bests, target)
    if pick is None and not asked and bests:
        # no [target] max_error: the default is a goal, not a reason to fail; the most accurate
        # verified family best within the limits is flashed, and the summary says it missed
        pick = sel.choose_most_accurate(bests, target)
    if bests and (pick is not None or any("bit_exact" in c.checks.get("host", {}) for c in bests.values())):
        sel.write_choice(outdir / C_DIR, bests, pick)
    section = {
        "target": target, "input_unit_um": problem.unit_um, "check_points": int(len(problem.check[0])),
        "check_set": ("grid + edge + random check inside the marks' hull, against the reference" if problem.reference
                      else "grid + edge + random check" if problem.analytic else "held-out rows"),
        "error_floor": problem.error_floor,
        "max_error_asked": asked,  # false: the default max_error, which a pick may miss (it is then the most accurate)
        "pick_meets_max_error": pick is not None and pick.meets(target["max_error"]),
        "implementations": [c.row(picked=c is pick) for c in bests.values()],
        "ladder": [c.row() for c in cands],
        "pick": None if pick is None else {"family": pick.family, "config": pick.config, "describe": pick.impl.describe(),
                                           "model_hash": pick.impl.source_hash(), "file": f"{problem.name}.c"},
        "inputs": pick_state.inputs_hash(outdir),  # the data key stored_bests reuses this selection by
    }
    if source != "ladder":
        section["source"] = source
    more = {"implementations": section["implementations"]}  # where issue 8 asked for the families' table
    if problem.reference is not None:
        more["reference"] = problem.reference.to_dict()
    write_metrics(outdir, {"selection": section, **more, **(extra(pick) if extra else {})})
    if pick is None:
        raise NnikError(sel.no_pick_reason(cands, bests, target, problem), problem.scn.source, "[target]")
    pick_state.seal(outdir, section)  # last: the pick, its metrics and hashes are all in place
    return section


TARGET_KEYS = ("chip", "max_error", "max_cycles", "max_flash_bytes")


def stored_bests(outdir: Path, target: dict, families: list[str]) -> list[tuple[str, dict]] | None:
    """Each family's ladder best as a finished ladder selection in OUTDIR recorded it, or None to
    fit the ladder again. Its key: the selection was made from these very data.npz and model.pt
    (their hashes), for the same [target] limits, and each family's C in c/alt/<family>/ is still
    the C it verified."""
    try:
        metrics = load_metrics(outdir)
    except NnikError:
        return None
    sec = metrics.get("selection")
    if not isinstance(sec, dict) or sec.get("source", "ladder") != "ladder" or not sec.get("inputs"):
        return None
    if sec["inputs"] != pick_state.inputs_hash(outdir):
        return None
    if any((sec.get("target") or {}).get(k) != target.get(k) for k in TARGET_KEYS):
        return None
    rows = {r["family"]: r for r in sec.get("implementations") or [] if "skipped" not in r}
    name = metrics.get("name")
    for fam in families:
        if fam not in rows or dir_hash(outdir / C_DIR / sel.ALT_DIR / fam, name) != rows[fam].get("c_hash"):
            return None
    return [(fam, rows[fam]["config"]) for fam in families]


def select(outdir: Path, progress: bool = True, families=None, target: dict | None = None) -> dict:
    """`nnik select`: the pipeline's stages on a finished OUTDIR (its model.pt and data.npz):
    fit every family's ladder, verify each family's best (host, avr, pic18), export the pick as
    c/NAME.{c,h} and every family's best as c/alt/<family>/; metrics["selection"]. ``target``
    overrides the scenario's [target] table (keys as there)."""
    problem = problem_for(outdir)
    target, asked = resolve_target(problem, target)  # a limit it refuses is refused here: nothing changed yet
    pick_state.invalidate(outdir)  # c/NAME.c and c/alt/ are about to change
    cands, bests = fit_bests(problem, target, families, progress)
    verify_bests(outdir, bests, progress)  # every family's best, whether or not one meets the target
    return conclude(outdir, problem, cands, bests, target, asked)
