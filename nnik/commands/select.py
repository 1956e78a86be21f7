"""`nnik select MODEL_DIR`: the pick again on a finished model directory, with other limits or
families (nnik.pipeline.select)."""

from __future__ import annotations

from nnik import pipeline
from nnik.commands import common_options as co, option_types as opt
from nnik.commands.model_dirs import add_model_dir, evaluated_dir
from nnik.report.console import print_selection

HELP = ("pick again on a model directory: fit every family, verify each family's best on the chips, export the "
        "cheapest that meets the target as c/NAME.c")
DESCRIPTION = (
    "Run `nnik run`'s family stages again on a model directory, with the limits given here in place of the "
    f"scenario's [target]: fit every implementation family ({co.FAMILY_LIST}) over its ladder on one contract, "
    "verify each family's best bit for bit on the host and the simulated chips, and export the one with the fewest "
    "cycles (then the least flash) on the target chip among those that meet max_error, max_cycles and "
    "max_flash_bytes as c/NAME.c (each family's best in c/alt/<family>/).")


def register(sub) -> None:
    p = co.add_command(sub, "select", HELP, DESCRIPTION, result=True)
    add_model_dir(p)
    co.add_target(p, "the chip the pick must be cheapest on (default: the scenario's [target] chip)")
    p.add_argument("--max-error", type=opt.MAX_ERROR, help="default: the scenario's [target] max_error")
    p.add_argument("--max-cycles", type=opt.MAX_CYCLES, help="default: the scenario's [target] max_cycles")
    p.add_argument("--max-flash-bytes", type=opt.MAX_FLASH_BYTES, help="default: the scenario's [target] max_flash_bytes")
    p.add_argument("--family", action="append", choices=co.FAMILIES, help="only these families (repeatable; default all)")
    p.set_defaults(func=cmd_select)


def cmd_select(args) -> dict:
    out = evaluated_dir(args.model_dir)
    target = {k: v for k, v in (("chip", args.target), ("max_error", args.max_error), ("max_cycles", args.max_cycles),
                                ("max_flash_bytes", args.max_flash_bytes)) if v is not None}
    try:
        return pipeline.select(out, families=args.family or None, target=target, progress=co.show_progress(args))
    finally:
        print_selection(pipeline.load_metrics(out))
