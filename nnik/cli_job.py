"""`nnik job`: its arguments and its command (a G-code job through the firmware's logic in Python
and on the simulated chip); the pipeline (and torch) is imported only for a scenario TOML."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

from nnik.errors import NnikError
from nnik.files.metrics import MODEL_FILE
from nnik.report.console import console


def add_job_parser(sub) -> None:
    p = sub.add_parser("job", help="run a G-code job through the firmware logic (Python and simulated Uno or Mega)")
    p.add_argument("scenario", help="scenario TOML (its build directory) or a model directory")
    p.add_argument("job", help="G-code file")
    p.add_argument("-o", "--outdir", help="model directory of the scenario TOML (default build/<name>/); "
                   "an error with a model directory as the first argument")
    p.add_argument("--seg-um", type=int, help="longest arc chord in um (default 500)")
    p.add_argument("--shaper", metavar="KIND",
                   help="input shaper on the chip: none, zv, mzv, zvd, ei, or auto (the one that meets [motion] "
                        "max_contour_um at the least job time); default: the scenario's [motion] shaper")
    p.add_argument("--precompensate", action="store_true",
                   help="write OUTDIR/job/JOB_precompensated.gcode (the job rewritten so the modelled belts' tip "
                        "follows the path) and run that instead")
    p.add_argument("--no-chip", action="store_true", help="Python model only, no simavr run")
    p.add_argument("--mcu", choices=("atmega328p", "atmega2560"), default="atmega328p",
                   help="the simulated chip: the Uno's atmega328p (default) or the Mega's atmega2560")
    p.set_defaults(func=cmd_job)


def cmd_job(args) -> None:
    from nnik.firmware.gcode.job import run_job
    from nnik.report.job_summary import JOB_HEADER, job_row

    if Path(args.scenario).is_dir():
        out = Path(args.scenario)
        if args.outdir and Path(args.outdir).resolve() != out.resolve():
            raise NnikError("-o picks the model directory of a scenario TOML; the first argument is already a model "
                            "directory, so give one or the other", args.outdir, "-o")
    else:
        from nnik.machine.scenario import load_scenario

        scn = load_scenario(args.scenario)
        from nnik import pipeline

        out = Path(args.outdir) if args.outdir else pipeline.default_outdir(scn)
    if not (out / MODEL_FILE).is_file():
        raise NnikError(f"no trained model (run `nnik run {args.scenario}` first)", str(out))
    from nnik.files.pick_state import require_deliverable

    require_deliverable(out, "job")  # the job runs the firmware: only the verified pick, never the MLP instead
    res = run_job(out, Path(args.job), seg_um=args.seg_um, use_chip=False if args.no_chip else None,
                  shaper=args.shaper, precompensate=args.precompensate, mcu=args.mcu)
    t = Table(title=f"G-code job {res['job']} on {res['scenario']} ({res['seconds']:.2f} s of motion)")
    t.add_column("item")
    t.add_column("result")
    for h, v in zip(JOB_HEADER, job_row(res)):
        t.add_row(h, v)
    console.print(t)
    if res.get("dynamics"):
        from nnik.report.job_dynamics import print_methods

        print_methods(console, res)
    chip = res["chip"]
    if "not_run" not in chip:
        console.print(f"self-test on simavr: {chip['selftest']}")
        if chip.get("end_s") is not None:
            console.print(f"simulated chip: {chip['segments_started']} segments, idle at {chip['end_s']:.3f} s "
                          f"({chip['motion_s']:.3f} s of motion; the model's {res['seconds']:.3f} s)")
        if not (chip["steps_equal"] and chip["replies_equal"] and chip["selftest_pass"]):
            raise NnikError("the simulated chip's steps or answers differ from the Python model", res["job"])
    console.print(f"plot: {res['png']}; figures: {Path(res['png']).with_suffix('.json')}")
