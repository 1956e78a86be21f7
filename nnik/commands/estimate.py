"""`nnik estimate MODEL_DIR --target CHIP`: the MLP's cycles, flash and RAM predicted without a
compiler or simulator, by the MLP family's cost model."""

from __future__ import annotations

from nnik import pipeline
from nnik.commands import common_options as co, option_types as opt
from nnik.commands.model_dirs import add_model_dir
from nnik.files.outdir import check_model_dir
from nnik.report.console import console

HELP = "predict the MLP's cycles, flash and RAM on a chip from its cost model (no compiler, no simulator)"
DESCRIPTION = (
    "Quantise the trained MLP and predict, without compiling or simulating, its cycles per IK call, time at "
    "--clock-hz, flash and RAM on the chip, from the MLP family's cost model calibrated on the simulators; a "
    "prediction outside what the calibration covered is marked UNVALIDATED. `nnik run` and `nnik verify` measure "
    "instead.")


def register(sub) -> None:
    p = co.add_command(sub, "estimate", HELP, DESCRIPTION, result=True)
    add_model_dir(p)
    co.add_target(p, "the chip: avr or pic18", required=True)
    p.add_argument("--compiler", help="profile, e.g. avr-gcc-Os, avr-gcc-O2, pic18-sdcc (default: the target's first)")
    p.add_argument("--clock-hz", type=opt.CLOCK_HZ, default=16_000_000, help="the chip's clock (default 16000000)")
    p.add_argument("--kernel", choices=("fast", "portable"), help="default: the scenario's [export] kernel")
    p.set_defaults(func=cmd_estimate)


def cmd_estimate(args) -> dict:
    from nnik.implementations.mlp.cost import estimate  # the MLP family's cost model

    out = check_model_dir(args.model_dir)
    model = pipeline.TrainedModel.load(out / pipeline.MODEL_FILE)
    ds = pipeline.Dataset.load(out / pipeline.DATA_FILE)
    im = pipeline.quantize_kernel(model, ds, args.kernel or model.scenario.export["kernel"])
    e = estimate(im, args.target, args.compiler, clock_hz=args.clock_hz)
    label = "" if e.get("validated", True) else "  (UNVALIDATED extrapolation)"
    console.print(f"{im.name} ({im.kernel} kernel) on {args.target} ({e['profile']}){label}: "
                  f"{e['cycles']:.0f} cycles = {e['us']:.1f} us at {args.clock_hz / 1e6:g} MHz, "
                  f"flash {e['flash_bytes']} B, RAM {e['ram_bytes']} B")
    return e
