"""`nnik run SCENARIO`: the main job, every stage of nnik.pipeline.run with its console lines;
`nnik generate` and `nnik train`, the MLP's first two stages alone, share its arguments."""

from __future__ import annotations

import time
from pathlib import Path

from nnik import pipeline
from nnik.commands import common_options as co, option_types as opt
from nnik.commands.model_dirs import OUTDIR_DEFAULT, scenario_outdir, warn_training
from nnik.commands.report import print_report
from nnik.report.console import console, print_accuracy, print_selection

HELP = (f"the main job: fit every family ({co.FAMILY_LIST}) to a scenario, verify each family's best on the "
        "host and the simulated chips, export the cheapest that meets [target] as c/NAME.c")
DESCRIPTION = (
    "Run the whole pipeline on a scenario TOML. Sample the workspace and label it with the exact IK (a measured "
    "machine: read its marks and fit a reference model to them). "
    f"Fit every implementation family ({co.FAMILY_LIST}) over its ladder of configurations on one contract: "
    "the same data, the same check set, the same pre-rounding max error. Verify each family's best bit for bit "
    "against its integer model on the host and on "
    "the simulated chips (avr-gcc + simavr, SDCC + gpsim). Pick the one with the fewest cycles (then the least "
    "flash) on the [target] chip among those that meet [target] max_error, max_cycles and max_flash_bytes, and "
    "write it to OUTDIR/c/NAME.c, each family's best to OUTDIR/c/alt/<family>/, the figures to metrics.json and "
    "the report to OUTDIR/report/. Next: `nnik job SCENARIO JOB.gcode` runs a G-code job on the simulated chip.")


NO_NORMALIZE = ("the MLP alone, trained on raw mm inputs without input normalisation (seed 004's Table 1 "
                "'without'; default OUTDIR build/<name>-no-normalize/): no other family, no pick")


def add_scenario_args(p, outdir_what: str, no_normalize: str = NO_NORMALIZE) -> None:
    p.add_argument("scenario", metavar="SCENARIO", help="scenario TOML file (datasets/*.toml, or your own)")
    co.add_outdir(p, outdir_what, OUTDIR_DEFAULT)
    p.add_argument("--no-normalize", action="store_true", help=no_normalize)


def register(sub) -> None:
    p = co.add_command(sub, "run", HELP, DESCRIPTION)
    add_scenario_args(p, "the model directory it writes: data, models, c/, metrics.json, report/")
    p.add_argument("--search", type=opt.TRIALS, metavar="N",
                   help="pick by an N-trial multi-objective design-space search (`nnik search`) instead of the "
                        "families' ladders")
    p.set_defaults(func=cmd_run)


def cmd_run(args) -> None:
    from nnik.machine.scenario import load_scenario

    t0 = time.perf_counter()
    scn = load_scenario(args.scenario)
    out = scenario_outdir(args, scn, create=True)
    console.print(f"[bold]nnik run[/bold] {scn.source} -> {out}/")
    if scn.servo is not None:  # a DC-servo xy_table: identify, tune, the closed loop (nnik.commands.servo_run)
        from nnik.commands.servo_run import run_servo

        run_servo(scn, out, lambda line: console.print(line, markup=False))
        console.print(f"done in {time.perf_counter() - t0:.1f} s")
        return
    if args.no_normalize:  # the MLP alone on raw mm inputs (seed 004's Table 1 'without'): no families, no pick
        print_generated(pipeline.generate(scn, out))
        warn_training(pipeline.train(scn, out, normalize=False))
        print_accuracy(pipeline.evaluate(out))
    else:
        from nnik.commands.search import search_and_print

        search_trials = getattr(args, "search", None)
        stages: list[str] = []

        def on_stage(stage, value):
            stages.append(stage)
            _print_stage(out, stage, value)

        try:
            res = pipeline.run(scn, out, progress=co.show_progress(args), on_stage=on_stage, pick=not search_trials)
        finally:
            if "mlp" in stages and not search_trials:  # the families were verified: their table, pick or not
                print_selection(pipeline.load_metrics(out))
        if search_trials:
            console.print(f"searching the design space ({search_trials} trials), verifying the front on host, avr "
                          "and pic18 ...")
            bests = [(fam, c.config) for fam, c in res["bests"].items()]
            search_and_print(out, search_trials, bests=bests)
    print_report(out)
    console.print(f"done in {time.perf_counter() - t0:.1f} s; metrics: {out / pipeline.METRICS_FILE}")


def print_generated(ds) -> None:
    console.print(f"generated {', '.join(f'{len(v)} {k}' for k, v in ds.p.items())} points ({ds.meta['sampling']})")


def _print_stage(out: Path, stage: str, value) -> None:
    """What `nnik run` says as each of pipeline.run's stages ends."""
    if stage == "data":
        print_generated(value.dataset)
        console.print("fitting every implementation family (the mlp trains as its family's fit) ...")
    elif stage == "fitted" and value[2] is not None:
        warn_training(value[2])  # the mlp family's network, as its fit trained it
    elif stage == "mlp":
        if value:
            console.print(f"mlp family: its network in {out / pipeline.MODEL_FILE}, its C (both kernels) in "
                          f"{out / pipeline.MLP_DIR}/, verified on {', '.join(value)}:")
        for target, res in value.items():
            if target == "host":
                continue
            if "not_run" in res:
                console.print(f"mlp family on {target}: not run ({res['not_run']})")
            else:
                console.print(f"mlp family on {target}: {res['cycles']:.0f} cycles/IK, {res['flash_bytes']} B flash, "
                              f"{res['mismatches']} mismatches on {res['points']} vectors")
        if value:
            console.print(f"mlp family: its accuracy table is `nnik evaluate {out}`")
            console.print("verifying each family's best on host, avr and pic18 ...")
