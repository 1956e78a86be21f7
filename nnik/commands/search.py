"""`nnik search OUTDIR_OR_SCENARIO`: the design-space search over every family's knobs
(nnik.search.study), its front verified on the chips and the pick made from it."""

from __future__ import annotations

from pathlib import Path

from nnik import pipeline
from nnik.commands import common_options as co, option_types as opt
from nnik.commands.model_dirs import OUTDIR_DEFAULT, scenario_outdir, trained_for, warn_training
from nnik.commands.report import print_report
from nnik.errors import NnikError
from nnik.files.outdir import check_model_dir
from nnik.report.console import console, print_front, print_selection

HELP = ("multi-objective search over every family's knobs (error, cycles, flash); verify the front on the chips "
        "and pick from it")
DESCRIPTION = (
    f"Search the design space of every implementation family ({co.FAMILY_LIST}) with Optuna's seeded NSGA-II "
    "sampler: each trial fits one configuration and scores its pre-rounding max error, estimated cycles on the "
    "[target] chip and estimated flash; [target]'s limits are the constraints. The Pareto front is then refitted, "
    "verified on the host and the simulated chips, and the pick is made and exported as `nnik run` does "
    "(c/NAME.c, c/alt/<family>/). Given a scenario TOML it first runs the families' ladders (their bests start "
    "the study). The study is kept (OUTDIR/search.journal or --storage): running again continues it up to --trials.")


def register(sub) -> None:
    p = co.add_command(sub, "search", HELP, DESCRIPTION)
    p.add_argument("source", metavar="OUTDIR_OR_SCENARIO", help="a model directory `nnik run` wrote, or a scenario TOML")
    co.add_outdir(p, "the model directory a scenario TOML's search writes", OUTDIR_DEFAULT)
    p.add_argument("--trials", type=opt.TRIALS, default=200, help="finished trials the study should hold (default 200)")
    p.add_argument("--storage", help="database URL, e.g. postgresql://USER@HOST:PORT/DB, or journal:///FILE (a journal "
                   "file other directories share; default OUTDIR/search.journal)")
    p.add_argument("--study", help="study name (default nnik-<scenario>)")
    p.add_argument("--jobs", type=opt.JOBS, default=1, help="local worker processes (default 1)")
    p.add_argument("--families", help=f"comma-separated families to search: {co.FAMILY_LIST} (default all)")
    p.add_argument("--worker", action="store_true", help="only run trials (another machine verifies and picks)")
    p.add_argument("--no-warm-start", action="store_true",
                   help="do not queue the families' ladder bests as a new study's first trials")
    p.add_argument("--show", action="store_true", help="print the study's front without running anything")
    p.set_defaults(func=cmd_search)


def search_and_print(out: Path, trials: int, args=None, bests=None) -> None:
    from nnik.search import study as search

    kw = {"bests": bests}
    if args is not None:
        kw.update(url=args.storage, name=args.study, jobs=args.jobs, worker_only=args.worker,
                  families=args.families.split(",") if args.families else None, warm_start=not args.no_warm_start)
    try:
        res = search.search(out, trials, **kw)
    finally:
        if not (args is not None and args.worker):
            print_selection(pipeline.load_metrics(out))
    s = res["search"]
    rate = f", {s['trials_per_min']:.1f} trials/min" if s.get("trials_per_min") else ""
    others = s["trials_added"] - s["trials_run"] if "trials_added" in s else 0
    console.print(f"search: {s['trials_run']} trials run by this command ({s['jobs']} local job"
                  f"{'s' * (s['jobs'] > 1)}) in {s['seconds']:.0f} s{rate}; the study holds {s.get('study_trials', '?')} "
                  f"finished trials (asked for {s.get('trials_target', '?')}"
                  + (f"; {others} run meanwhile by other workers" if others else "")
                  + f") ({s['storage']} storage, study {s['study']})")
    if "front" in s:
        console.print(f"front: {len(s['front'])} points ({s['feasible_front']} on the front of those that meet "
                      f"\\[target]), families {', '.join(s['front_families'])}")


def cmd_search(args) -> None:
    from nnik.search import study as search

    src = Path(args.source)
    bests = None  # each family's ladder best, when this command fits the ladder
    if src.is_dir():
        out = check_model_dir(src, pipeline.C_DIR)
    else:
        from nnik.machine.scenario import load_scenario

        scn = load_scenario(src)
        out = scenario_outdir(args, scn, create=True)
        if not trained_for(scn, out):
            if args.show:
                raise NnikError("no trained model for this scenario here (run `nnik search` or `nnik run` first)", str(out))
            console.print(f"[bold]nnik search[/bold] {scn.source} -> {out}/: the data and the families' ladders "
                          "first (the mlp trains as its family's fit)")
            fams = search.searched_families(args.families.split(",") if args.families else None)
            # the mlp's ladder (its network is the study's model.pt), and the searched families' for
            # the warm start
            fams = ["mlp"] if args.no_warm_start else list(dict.fromkeys(["mlp", *fams]))
            res = pipeline.run(scn, out, progress=co.show_progress(args), pick=False, mlp_verify=(), families=fams)
            warn_training(pipeline.load_pair(out)[0])
            bests = [(fam, c.config) for fam, c in res["bests"].items()]
    if not (out / pipeline.MODEL_FILE).is_file():
        raise NnikError("no trained model (run `nnik run` first)", str(out))
    if args.show:
        res = search.show(out, args.storage, args.study)
        print_front(res, pipeline.load_pair(out)[0].scenario.unit)
        return
    search_and_print(out, args.trials, args, bests)
    if not args.worker:
        print_report(out)
