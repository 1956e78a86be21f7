"""`nnik synth-csv`: a calibration CSV measured on a simulated machine, written atomically and
never over one of its inputs (the scenario, or a CSV the scenario reads)."""

from __future__ import annotations

from pathlib import Path

from nnik.commands import common_options as co, option_types as opt
from nnik.report.console import console

HELP = "write a calibration CSV 'measured' on a simulated machine (for a measured-machine scenario)"
DESCRIPTION = (
    "Simulate measuring an analytic scenario's machine: command the head to N marks in its [workspace], read where "
    "it went with --noise-um of measurement noise, and write the CSV (x_um,y_um,q1,q2) a measured-machine scenario "
    "reads ([mechanism] kind = \"measured\"). The same scenario and --seed give the same CSV.")


def register(sub) -> None:
    p = co.add_command(sub, "synth-csv", HELP, DESCRIPTION)
    p.add_argument("scenario", metavar="SCENARIO", help="scenario of the machine to 'measure' (an analytic one)")
    co.add_output_file(p, "the calibration CSV it writes (x_um,y_um,q1,q2)", required=True)
    p.add_argument("-n", type=opt.SYNTH_N, default=400, help="number of measured points (default 400)")
    p.add_argument("--noise-um", type=opt.NOISE_UM, default=2.0, help="measurement noise, 1 sigma, per axis (default 2)")
    p.add_argument("--readings", choices=("commanded", "rounded"), default="commanded",
                   help="commanded: whole-step commands, the position measured (default); rounded: the head on each "
                   "mark, q1/q2 the step counter's whole-step reading (+-0.5 of rounding)")
    p.add_argument("--sampling", choices=("sobol", "grid"), default="sobol",
                   help="scattered (sobol) marks or a k x k grid (k = ceil(sqrt(n)))")
    p.add_argument("--inset-mm", type=opt.INSET_MM, default=0.05, help="marks this far inside [workspace] (default 0.05)")
    co.add_seed(p, "the marks and the measurement noise", "CSV")
    p.set_defaults(func=cmd_synth_csv)


def scenario_inputs(scn) -> list[Path]:
    """The files a scenario was read from: its TOML and a measured machine's CSV."""
    csv = getattr(scn.mechanism, "csv_path", None)
    return [Path(p) for p in (scn.source, csv) if p is not None]


def cmd_synth_csv(args) -> None:
    from nnik.files.atomic_write import write_file_atomic
    from nnik.files.output_path import check_output_file
    from nnik.machine.scenario import load_scenario
    from nnik.machine.synth import measurements_csv

    scn = load_scenario(args.scenario)
    out = check_output_file(Path(args.output), [Path(args.scenario), *scenario_inputs(scn)], "the CSV")
    text, n = measurements_csv(scn, args.n, args.noise_um, args.seed, readings=args.readings, sampling=args.sampling,
                               inset_mm=args.inset_mm)
    write_file_atomic(out, text)  # a kill or a full disk leaves the old file or none, never half a CSV
    how = "whole-step counter readings at the marks" if args.readings == "rounded" else "whole-step commands"
    console.print(f"wrote {out}: {n} rows from {scn.source} ({args.sampling}, {how}) with {args.noise_um:g} um "
                  "position noise")
