"""`nnik synth-csv`: a calibration CSV measured on a simulated machine, written atomically and
never over one of its inputs (the scenario, or a CSV the scenario reads)."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

console = Console()


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
