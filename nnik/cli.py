"""The `nnik` command line. Bad input ends in one line on stderr and exit code 2."""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from rich.table import Table

from nnik import pipeline
from nnik.commands import option_types as opt
from nnik.errors import NnikError, NnikWarning, warning_line
from nnik.files.atomic_write import reraise_lost_interrupts
from nnik.files.os_errors import os_error_line
from nnik.files.outdir import check_model_dir, check_outdir, release_locks
from nnik.report.console import console, print_accuracy, print_front, print_selection


def _outdir(args, scn, create: bool = False) -> Path:
    out = Path(args.outdir) if args.outdir else pipeline.default_outdir(scn, not args.no_normalize)
    return check_outdir(out, create=create)


def _warn_training(model) -> None:
    """The user's wall-clock cap cut training short: the model depends on this machine's load."""
    stop = getattr(model, "stopped_by", "budget")
    if stop != "budget":
        console.print(f"[bold yellow]warning:[/bold yellow] training stopped by the {stop.replace('_', '-')} cap "
                      f"(\\[training] max_seconds) before its iteration budget; the result depends on machine load and is not reproducible "
                      f"(recorded as training.stopped_by in metrics.json)")


def cmd_run(args) -> None:
    from nnik.machine.scenario import load_scenario

    t0 = time.perf_counter()
    scn = load_scenario(args.scenario)
    out = _outdir(args, scn, create=True)
    console.print(f"[bold]nnik run[/bold] {scn.source} -> {out}/")
    if args.no_normalize:  # the MLP alone on raw mm inputs (seed 004's Table 1 'without'): no families, no pick
        _print_generated(pipeline.generate(scn, out))
        _warn_training(pipeline.train(scn, out, normalize=False))
        print_accuracy(pipeline.evaluate(out))
    else:
        search_trials = getattr(args, "search", None)
        stages: list[str] = []

        def on_stage(stage, value):
            stages.append(stage)
            _print_stage(out, stage, value)

        try:
            res = pipeline.run(scn, out, progress=sys.stderr.isatty(), on_stage=on_stage, pick=not search_trials)
        finally:
            if "mlp" in stages and not search_trials:  # the families were verified: their table, pick or not
                print_selection(pipeline.load_metrics(out))
        if search_trials:
            console.print(f"searching the design space ({search_trials} trials), verifying the front on host, avr "
                          "and pic18 ...")
            bests = [(fam, c.config) for fam, c in res["bests"].items()]
            _search_and_print(out, search_trials, bests=bests)
    print_report(out)
    console.print(f"done in {time.perf_counter() - t0:.1f} s; metrics: {out / pipeline.METRICS_FILE}")


def _print_generated(ds) -> None:
    console.print(f"generated {', '.join(f'{len(v)} {k}' for k, v in ds.p.items())} points ({ds.meta['sampling']})")


def _print_stage(out: Path, stage: str, value) -> None:
    """What `nnik run` says as each of pipeline.run's stages ends."""
    if stage == "data":
        _print_generated(value.dataset)
        console.print("fitting every implementation family (the mlp trains as its family's fit) ...")
    elif stage == "fitted" and value[2] is not None:
        _warn_training(value[2])  # the mlp family's network, as its fit trained it
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


def _search_and_print(out: Path, trials: int, args=None, bests=None) -> None:
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

    src = Path(args.target)
    bests = None  # each family's ladder best, when this command fits the ladder
    if src.is_dir():
        out = check_model_dir(src, pipeline.C_DIR)
    else:
        from nnik.machine.scenario import load_scenario

        scn = load_scenario(src)
        args.no_normalize = False
        out = _outdir(args, scn, create=True)
        if not _trained_for(scn, out):
            if args.show:
                raise NnikError("no trained model for this scenario here (run `nnik search` or `nnik run` first)", str(out))
            console.print(f"[bold]nnik search[/bold] {scn.source} -> {out}/: the data and the families' ladders "
                          "first (the mlp trains as its family's fit)")
            fams = search.searched_families(args.families.split(",") if args.families else None)
            # the mlp's ladder (its network is the study's model.pt), and the searched families' for
            # the warm start
            fams = ["mlp"] if args.no_warm_start else list(dict.fromkeys(["mlp", *fams]))
            res = pipeline.run(scn, out, progress=sys.stderr.isatty(), pick=False, mlp_verify=(), families=fams)
            _warn_training(pipeline.load_pair(out)[0])
            bests = [(fam, c.config) for fam, c in res["bests"].items()]
    if not (out / pipeline.MODEL_FILE).is_file():
        raise NnikError("no trained model (run `nnik run` first)", str(out))
    if args.show:
        res = search.show(out, args.storage, args.study)
        print_front(res, pipeline.load_pair(out)[0].scenario.unit)
        return
    _search_and_print(out, args.trials, args, bests)
    if not args.worker:
        print_report(out)


def _trained_for(scn, out: Path) -> bool:
    """OUTDIR holds data.npz and model.pt of this very scenario (a rerun resumes, no retraining)."""
    if not ((out / pipeline.DATA_FILE).is_file() and (out / pipeline.MODEL_FILE).is_file()
            and (out / pipeline.METRICS_FILE).is_file()):
        return False
    try:
        model, _ = pipeline.load_pair(out)
    except NnikError:
        return False
    return model.scenario.fingerprint == scn.fingerprint


def cmd_generate(args) -> None:
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(args.scenario)
    out = _outdir(args, scn, create=True)
    ds = pipeline.generate(scn, out)
    console.print(f"wrote {out / pipeline.DATA_FILE}: {', '.join(f'{len(v)} {k}' for k, v in ds.p.items())} points")


def cmd_train(args) -> None:
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(args.scenario)
    out = _outdir(args, scn)
    model = pipeline.train(scn, out, normalize=False if args.no_normalize else None)
    _warn_training(model)
    console.print(f"wrote {out / pipeline.MODEL_FILE} and {out / pipeline.ONNX_FILE} ({model.train_seconds:.1f} s)")


def cmd_evaluate(args) -> None:
    print_accuracy(pipeline.evaluate(check_model_dir(args.model_dir)))


EVALUATED_KEYS = ("name", "unit", "outputs", "network", "dataset", "float", "affine_only", "onnx")


def _evaluated_dir(model_dir) -> Path:
    """A model directory whose metrics.json `nnik evaluate` wrote (checked before anything runs)."""
    out = check_model_dir(model_dir, pipeline.C_DIR)
    missing = [k for k in EVALUATED_KEYS if k not in pipeline.load_metrics(out)]
    if missing:
        raise NnikError(f"metrics.json lacks {', '.join(missing)} (run `nnik evaluate` again)", str(out))
    return out


def cmd_export(args) -> None:
    out = _evaluated_dir(args.model_dir)
    if args.arduino is not None:
        from nnik.files.pick_state import require_deliverable
        from nnik.firmware.arduino import check_libdir

        # the library is firmware: only a finished pick whose c/NAME.c is the verified C (refused
        # before anything is written; the MLP is never delivered in its place)
        require_deliverable(out, "export --arduino")
        check_libdir(Path(args.arduino), out)  # DIR too, before c/ is touched
    im, _ = pipeline.export(out)
    console.print(f"wrote {out / pipeline.C_DIR}/{im.name}.h and {im.name}.c ({im.weights_bytes()} bytes of tables)")
    if args.arduino is not None:
        from nnik.firmware.arduino import export_arduino

        lib = export_arduino(out, Path(args.arduino))
        console.print(f"wrote Arduino library {lib['libname']} to {lib['dir']}/ (examples {lib['name']}_selftest with "
                      f"{lib['golden']} golden vectors, {lib['name']}_gcode)")
    print_accuracy(pipeline.load_metrics(out))


def cmd_select(args) -> None:
    out = _evaluated_dir(args.model_dir)
    target = {k: v for k, v in (("chip", args.chip), ("max_error", args.max_error), ("max_cycles", args.max_cycles),
                                ("max_flash_bytes", args.max_flash_bytes)) if v is not None}
    try:
        pipeline.select(out, families=args.family or None, target=target, progress=sys.stderr.isatty())
    finally:
        print_selection(pipeline.load_metrics(out))


def cmd_verify(args) -> None:
    """The pick (c/NAME.c as it is on disk) by default, a family's best (c/alt/F/) with --family,
    the MLP pipeline's kernels and the float IK (c/mlp/, what `nnik export` wrote) with
    --mlp-pipeline; always on the host, and on --target's simulator."""
    out = _evaluated_dir(args.model_dir)
    if args.mlp_pipeline:
        res = pipeline.verify(out, args.target)
        print_accuracy(pipeline.load_metrics(out))
        if not res.get("bit_exact", False):
            raise NnikError(f"{args.target}: {res.get('mismatches')} mismatches between the C and the integer model")
        return
    from nnik.firmware import pick_verify

    name = pipeline.load_metrics(out)["name"]
    if args.family:
        _, res = pick_verify.verify_family(out, args.family, args.target)
        what, st = f"c/alt/{args.family}/{name}.c", None
    else:
        st, res = pick_verify.verify_pick(out, args.target)
        what = st.file
    for k, r in res.items():
        if "not_run" in r:
            console.print(f"{what}: {k}: not run ({r['not_run']})")
        elif "cycles" in r:
            console.print(f"{what} ({r['c_hash']}): {k}: {r['cycles']:.0f} cycles, {r['flash_bytes']} B flash, "
                          f"{r['mismatches']} mismatches on {r['points']} vectors ({r['path']} path)")
        else:
            console.print(f"{what} ({r['c_hash']}): {k}: {r['mismatches']} mismatches on {r['points']} points")
    bad = {k: r for k, r in res.items() if "not_run" not in r and not r["bit_exact"]}
    if bad:
        again = f"; `nnik select {out}` writes the verified pick again" if st is not None else ""
        raise NnikError(f"{what} as it is on disk differs from its integer model: "
                        + ", ".join(f"{r['mismatches']} mismatches on {k}" for k, r in bad.items()) + again, str(out))
    if args.target != "host" and "not_run" in res.get(args.target, {}):
        raise NnikError(f"{args.target}: not run ({res[args.target]['not_run']})", str(out))
    if st is not None:
        console.print(st.message if st.ok else f"not yet deliverable: {st.message}")


def cmd_estimate(args) -> None:
    from nnik.estimate import estimate

    out = check_model_dir(args.model_dir)
    model = pipeline.TrainedModel.load(out / pipeline.MODEL_FILE)
    ds = pipeline.Dataset.load(out / pipeline.DATA_FILE)
    im = pipeline.quantize_kernel(model, ds, args.kernel or model.scenario.export["kernel"])
    e = estimate(im, args.target, args.compiler, clock_hz=args.clock_hz)
    label = "" if e.get("validated", True) else "  (UNVALIDATED extrapolation)"
    console.print(f"{im.name} ({im.kernel} kernel) on {args.target} ({e['profile']}){label}: "
                  f"{e['cycles']:.0f} cycles = {e['us']:.1f} us at {args.clock_hz / 1e6:g} MHz, "
                  f"flash {e['flash_bytes']} B, RAM {e['ram_bytes']} B")


def cmd_tanh(args) -> None:
    from nnik.implementations.mlp import tanh as activations

    rows = activations.variants_table()
    t = Table(title="tanh replacements: int16 Q3.12 in, Q15 out, all 65536 inputs swept (errors in LSB of Q15)")
    for c in ("variant", "form", "segments", "degree", "float max", "float RMS", "int max LSB", "int RMS LSB",
              "mults", "bytes"):
        t.add_column(c, justify="left" if c in ("variant", "form") else "right")
    for r in rows:
        name = r["name"] + (" (default)" if r["default"] else "")
        t.add_row(name, r["form"], str(r["segments"]), str(r["degree"]), f"{r['float_max']:.2e}",
                  f"{r['float_rms']:.2e}", f"{r['int_max_lsb']:.2f}", f"{r['int_rms_lsb']:.3f}", str(r["mults"]),
                  str(r["bytes"]))
    console.print(t)
    for r in rows:
        console.print(f"  {r['name']}: {r['description']}")
    rep = activations.paper_report()
    console.print(f"seed 000's configuration ([0,1], (1,2], (2,3], (3,5.3], degree 5, least squares): our fit RMS "
                  f"{rep['fit_rms_0_5p3']:.3e} and max {rep['fit_max_0_5p3']:.3e} on [0, 5.3]; the paper's printed "
                  f"coefficients give RMS {rep['printed_rms_0_6']:.4e} on [0, 6] (published: {rep['published_rms']:.4e})")


def print_report(model_dir: Path, out_dir: Path | None = None) -> None:
    from nnik.report import SUMMARY_HEADER, load_metrics, summary_rows, write_report

    index = write_report(model_dir, out_dir)
    t = Table(title=f"report: {index}")
    for h in SUMMARY_HEADER:
        t.add_column(h)
    for r in summary_rows(load_metrics(model_dir)):
        t.add_row(*r)
    console.print(t)


def cmd_report(args) -> None:
    print_report(check_model_dir(args.model_dir), check_outdir(Path(args.outdir)) if args.outdir else None)


def build_parser() -> argparse.ArgumentParser:
    ap = opt.OneLineParser(prog="nnik", description="Inverse kinematics as verified fixed-point C for 8-bit MCUs.")
    sub = ap.add_subparsers(dest="command", required=True)

    def scenario_cmd(name, func, help_):
        p = sub.add_parser(name, help=help_)
        p.add_argument("scenario", help="scenario TOML file")
        p.add_argument("-o", "--outdir", help="output directory (default build/<name>/)")
        p.add_argument("--no-normalize", action="store_true", help="train on raw mm inputs (seed 004's Table 1 'without')")
        p.set_defaults(func=func)
        return p

    p = scenario_cmd("run", cmd_run, "generate, train, export and evaluate a scenario")
    p.add_argument("--search", type=opt.TRIALS, metavar="N", help="pick by an N-trial design-space search, not the ladder")
    scenario_cmd("generate", cmd_generate, "sample the workspace and label it with the exact IK")
    scenario_cmd("train", cmd_train, "train the MLP on OUTDIR/data.npz, write model.pt and model.onnx")
    p = sub.add_parser("evaluate", help="accuracy of a trained model against the truth")
    p.add_argument("model_dir")
    p.set_defaults(func=cmd_evaluate)
    p = sub.add_parser("export", help="quantise a trained model and write its fixed-point C")
    p.add_argument("model_dir")
    p.add_argument("--arduino", metavar="DIR", help="also write an Arduino/PlatformIO library (self-test, G-code sketch)")
    p.set_defaults(func=cmd_export)
    p = sub.add_parser("select", help="fit every implementation family, verify each family's best on the chips, "
                                      "export the cheapest that meets the target as c/NAME.c")
    p.add_argument("model_dir")
    p.add_argument("--chip", choices=("avr", "pic18"), help="default: the scenario's [target] chip")
    p.add_argument("--max-error", type=opt.MAX_ERROR, help="default: the scenario's [target] max_error")
    p.add_argument("--max-cycles", type=opt.MAX_CYCLES)
    p.add_argument("--max-flash-bytes", type=opt.MAX_FLASH_BYTES)
    p.add_argument("--family", action="append", choices=("mlp", "poly", "lut", "hybrid"),
                   help="only these families (repeatable; default all)")
    p.set_defaults(func=cmd_select)
    p = sub.add_parser("verify", help="run the C on disk (the pick by default) and compare it bit for bit with its "
                                      "integer model, on the host and on --target")
    p.add_argument("model_dir")
    p.add_argument("--target", default="host", choices=("host", "avr", "pic18"),
                   help="host, or a simulated chip (the host runs too)")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--family", choices=("mlp", "poly", "lut", "hybrid"),
                      help="the family's best in c/alt/FAMILY/ instead of the pick in c/NAME.c")
    what.add_argument("--mlp-pipeline", action="store_true",
                      help="the scenario's MLP in c/mlp/ (both kernels) and the float IK, as `nnik export` wrote them")
    p.set_defaults(func=cmd_verify)
    p = sub.add_parser("estimate", help="static prediction of cycles, flash and RAM on a target")
    p.add_argument("model_dir")
    p.add_argument("--target", required=True, choices=("avr", "pic18"))
    p.add_argument("--compiler", help="profile, e.g. avr-gcc-Os, avr-gcc-O2, pic18-sdcc (default: the target's first)")
    p.add_argument("--clock-hz", type=opt.CLOCK_HZ, default=16_000_000)
    p.add_argument("--kernel", choices=("fast", "portable"), help="default: the scenario's [export] kernel")
    p.set_defaults(func=cmd_estimate)
    p = sub.add_parser("report", help="write the HTML/Markdown accuracy and latency report")
    p.add_argument("model_dir")
    p.add_argument("-o", "--outdir", help="report directory (default MODEL_DIR/report)")
    p.set_defaults(func=cmd_report)
    p = sub.add_parser("search", help="multi-objective search over every family's knobs; verify the front, pick")
    p.add_argument("target", metavar="OUTDIR_OR_SCENARIO", help="a trained output directory or a scenario TOML")
    p.add_argument("-o", "--outdir", help="output directory for a scenario TOML (default build/<name>/)")
    p.add_argument("--trials", type=opt.TRIALS, default=200, help="finished trials the study should hold (default 200)")
    p.add_argument("--storage", help="database URL, e.g. postgresql://USER@HOST:PORT/DB, or journal:///FILE (a journal "
                   "file other directories share; default OUTDIR/search.journal)")
    p.add_argument("--study", help="study name (default nnik-<scenario>)")
    p.add_argument("--jobs", type=opt.JOBS, default=1, help="local worker processes (default 1)")
    p.add_argument("--families", help="comma-separated families to search (default all)")
    p.add_argument("--worker", action="store_true", help="only run trials (another machine verifies and picks)")
    p.add_argument("--no-warm-start", action="store_true", help="do not queue the families' ladders as a new study's first trials")
    p.add_argument("--show", action="store_true", help="print the study's front without running anything")
    p.set_defaults(func=cmd_search)
    p = sub.add_parser("tanh", help="table of the tanh replacements and their measured errors")
    p.set_defaults(func=cmd_tanh)
    p = sub.add_parser("synth-csv", help="write a calibration CSV measured on a simulated machine")
    p.add_argument("scenario", help="scenario of the machine to 'measure' (an analytic one)")
    p.add_argument("-o", "--output", required=True, help="CSV to write (x_um,y_um,q1,q2)")
    p.add_argument("-n", type=opt.SYNTH_N, default=400, help="number of measured points")
    p.add_argument("--noise-um", type=opt.NOISE_UM, default=2.0, help="measurement noise, 1 sigma, per axis")
    p.add_argument("--readings", choices=("commanded", "rounded"), default="commanded",
                   help="commanded: whole-step commands, the position measured (default); rounded: the head on each "
                   "mark, q1/q2 the step counter's whole-step reading (+-0.5 of rounding)")
    p.add_argument("--sampling", choices=("sobol", "grid"), default="sobol",
                   help="scattered (sobol) marks or a k x k grid (k = ceil(sqrt(n)))")
    p.add_argument("--inset-mm", type=opt.INSET_MM, default=0.05, help="marks this far inside [workspace] (default 0.05)")
    p.add_argument("--seed", type=opt.SEED, default=0)
    from nnik.commands import job as job_command, shaper_calibrate
    from nnik.commands.synth_csv import cmd_synth_csv

    p.set_defaults(func=cmd_synth_csv)

    job_command.register(sub)
    shaper_calibrate.register(sub)
    opt.check_paths(ap)
    return ap


def main(argv: list[str] | None = None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help (0), or a bad option: the one line was printed (2)
        return exc.code if isinstance(exc.code, int) else 2
    reraise_lost_interrupts()
    # numpy's RuntimeWarnings are held back: after an error the one error line is all that shows;
    # after success they follow the output, one line each, so nothing is lost.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        warnings.simplefilter("always", NnikWarning)
        try:
            args.func(args)
        except NnikError as exc:
            print(f"nnik: error: {exc}", file=sys.stderr)
            return 2
        except OSError as exc:  # a full disk, a read-only place: one line (what nnik trusts is written atomically)
            print(f"nnik: error: {os_error_line(exc)}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            print("nnik: interrupted", file=sys.stderr)
            return 130
        finally:
            release_locks()
    for w in {(str(w.message), w.filename, w.lineno): w for w in caught}.values():
        print(warning_line(w), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
