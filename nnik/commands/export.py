"""`nnik export MODEL_DIR`: the MLP's fixed-point C (c/mlp/), and with --arduino the pick's
Arduino/PlatformIO library."""

from __future__ import annotations

from pathlib import Path

from nnik import pipeline
from nnik.errors import NnikError
from nnik.commands import common_options as co
from nnik.commands.model_dirs import add_model_dir, evaluated_dir
from nnik.job.servo_dir import KINDS as SERVO_KINDS
from nnik.report.console import console, print_accuracy

HELP = "quantise the trained MLP and write its fixed-point C to c/mlp/; --arduino: the pick's Arduino library"
DESCRIPTION = (
    "Quantise the trained MLP (model.pt) and write its fixed-point C to MODEL_DIR/c/mlp/ (the scenario's kernel, "
    "and the other kernel in c/mlp/<kernel>/ for comparison) and the float math.h IK to c/NAME_float.c, after the "
    "range analysis proves no tensor overflows. With --arduino DIR, also write an Arduino/PlatformIO library around "
    "the verified pick c/NAME.c (a self-test sketch with golden vectors and a G-code sketch); only a finished pick "
    "is delivered, never the MLP in its place.")


def register(sub) -> None:
    p = co.add_command(sub, "export", HELP, DESCRIPTION)
    add_model_dir(p)
    p.add_argument("--arduino", metavar="DIR", help="also write the pick's Arduino/PlatformIO library to this "
                   "directory (self-test and G-code example sketches)")
    p.add_argument("--job", metavar="JOB.gcode", help="a dc_servo xy_table: the job the library stores in flash "
                   "(default: the seed's circle, datasets/jobs/servo_circle.gcode)")
    p.add_argument("--controller", choices=SERVO_KINDS, help="a dc_servo xy_table: the tuned or pretrained "
                   "controller to export (default: the one `nnik run` chose)")
    p.set_defaults(func=cmd_export)


def cmd_export(args) -> None:
    from nnik.job.servo_dir import is_servo_dir

    if is_servo_dir(Path(args.model_dir)):  # a DC-servo xy_table: the controller's library (nnik.commands.servo_export)
        from nnik.commands.servo_export import cmd_servo_export

        return cmd_servo_export(args)
    if args.job is not None or args.controller is not None:
        raise NnikError("only a dc_servo xy_table's export stores a job and names a controller", None,
                        "--job" if args.job is not None else "--controller")
    out = evaluated_dir(args.model_dir)
    if args.arduino is not None:
        from nnik.files.pick_state import require_deliverable
        from nnik.firmware.arduino import check_libdir

        # the library is firmware: only a finished pick whose c/NAME.c is the verified C (refused
        # before anything is written; the MLP is never delivered in its place)
        require_deliverable(out, "export --arduino")
        check_libdir(Path(args.arduino), out)  # DIR too, before c/ is touched
    im, _ = pipeline.export(out)
    console.print(f"wrote {out / pipeline.MLP_DIR}/{im.name}.h and {im.name}.c ({im.weights_bytes()} bytes of tables)")
    if args.arduino is not None:
        from nnik.firmware.arduino import export_arduino

        lib = export_arduino(out, Path(args.arduino))
        console.print(f"wrote Arduino library {lib['libname']} to {lib['dir']}/ (examples {lib['name']}_selftest with "
                      f"{lib['golden']} golden vectors, {lib['name']}_gcode)")
        if not lib["uno_fits"]:
            console.print("[yellow]warning:[/] the Uno's G-code build does not fit its flash with any choice of "
                          "options (the IK, the shaper and the planner fill it): build the sketch for the "
                          "ATmega2560 (Mega), or lower sample_hz / drop the shaper")
        elif lib["uno_left_out"]:
            console.print(f"the Uno's build leaves out {', '.join(lib['uno_left_out'])} to fit its flash "
                          "(error:20; the Mega's carries every option)")
    print_accuracy(pipeline.load_metrics(out))
