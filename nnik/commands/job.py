"""`nnik job`: a G-code job through the firmware logic in Python and on the simulated Uno."""

from __future__ import annotations

import sys
from pathlib import Path

from rich.console import Console
from rich.table import Table
from rich.text import Text

from nnik.commands import common_options as co, option_types as opt
from nnik.commands.model_dirs import OUTDIR_DEFAULT
from nnik.errors import NnikError
from nnik.files.outdir import JOB_DIR, check_model_dir
from nnik.job.servo_dir import KINDS as SERVO_KINDS

console = Console(markup=False)  # text, not markup: "[motion] max_contour_um", "- (no [dynamics])" as they are

HELP = "run a G-code job on the simulated chip through the pick's firmware, step for step against the Python model"
DESCRIPTION = ("Run a G-code file that CAM, a slicer, a laser or plotter tool wrote through the chip's firmware: its "
               "flavour and tool rule are detected (and said), it is planned with acceleration, shaped, run through "
               "the pick's IK (c/NAME.c) in Python and on the simulated chip (simavr), step for step; the contour "
               "error is measured against the programmed path. Writes MODEL_DIR/job/JOB.json and JOB.png.")


def register(sub) -> None:
    p = co.add_command(sub, "job", HELP, DESCRIPTION, result=True)
    p.add_argument("scenario", metavar="SCENARIO", help="scenario TOML (its model directory is -o's) or a model directory")
    p.add_argument("job", metavar="JOB", help="G-code file")
    co.add_outdir(p, "the scenario TOML's model directory, where the job's files go (its job/ folder); not with a "
                  "model directory as SCENARIO", OUTDIR_DEFAULT)
    p.add_argument("--check", action="store_true", help="parse and plan only, as grbl's $C: extent, motion time, "
                   "tool-on length and every noted word; writes nothing")
    p.add_argument("--fit", action="store_true", help="scale the job down uniformly (never up) to fit the workspace and "
                   "centre it")
    p.add_argument("--scale", type=opt.SCALE, help="scale the job by S about the work origin")
    p.add_argument("--offset", type=opt.pair, metavar="X,Y", help="move the job by X,Y in its units (mm, or inches for a "
                   "G20 job)")
    p.add_argument("--flavour", help="grbl, marlin or linuxcnc (default: detected from the file)")
    p.add_argument("--tool", help="the machine's tool: laser, pen, servo, spindle, knife or none (default: the "
                   "scenario's [tool] kind)")
    p.add_argument("--tool-rule", choices=("s", "z", "e", "m300", "none"),
                   help="how the job turns the tool on: s (M3/M4 S), z (Z at or below the threshold), e (Marlin: a "
                        "move that extrudes), m300 (M300 S servo pen), none (default: from the tool and the file)")
    p.add_argument("--tool-z", type=opt.TOOL_Z, metavar="MM", help="a pen, spindle or knife is down at or below this Z "
                   "(default: the scenario's [tool] pen_z_um, 0)")
    p.add_argument("--seg-um", type=opt.SEG_UM, help="longest arc chord in um (default 500)")
    p.add_argument("--shaper", metavar="KIND",
                   help="input shaper on the chip: none, zv, mzv, zvd, ei, 2hump_ei, 3hump_ei, or auto (the one that "
                        "meets [motion] max_contour_um at the least job time); default: the scenario's [shaper] table "
                        "or [motion] shaper")
    p.add_argument("--precompensate", action="store_true",
                   help="write OUTDIR/job/JOB_precompensated.gcode (the job rewritten so the modelled belts' tip "
                        "follows the path) and run that instead")
    p.add_argument("--no-chip", action="store_true", help="Python model only, no simavr run")
    p.add_argument("--controller", choices=SERVO_KINDS,
                   help="a dc_servo xy_table's controller (default: the one `nnik run` chose)")
    p.add_argument("--mcu", choices=("atmega328p", "atmega2560"), default="atmega328p",
                   help="the simulated chip: the Uno's atmega328p (default) or the Mega's atmega2560")
    p.add_argument("--protocol", choices=("counting", "send-response"), default="counting",
                   help="how the simulated sender streams the lines: counting (grbl's character counting, as grbl "
                        "senders do: unanswered lines fill the firmware's receive buffer; default) or send-response "
                        "(the next line only after the previous one's answer)")
    p.set_defaults(func=cmd_job)


def _model_dir(args):
    """(the model directory, the scenario whose [motion], [dynamics] and [tool] the job runs with).

    With a scenario TOML its model directory must hold a model of that very machine (the same
    fingerprint: name, mechanism, actuator, workspace, data and network); the TOML's own [motion],
    [dynamics] and [tool], which the trained IK does not depend on, are the truth, edits included.
    With a model directory: the scenario it was trained with (its model.pt's copy)."""
    from nnik import pipeline
    from nnik.firmware.ik_oracle import load_scenario_of

    scn = None
    if Path(args.scenario).is_dir():
        out = Path(args.scenario)
        if args.outdir and Path(args.outdir).resolve() != out.resolve():
            raise NnikError("-o picks the model directory of a scenario TOML; the first argument is already a model "
                            "directory, so give one or the other", args.outdir, "-o")
    else:
        from nnik.machine.scenario import load_scenario

        scn = load_scenario(args.scenario)
        out = Path(args.outdir) if args.outdir else pipeline.default_outdir(scn)
    if not (out / pipeline.MODEL_FILE).is_file():
        raise NnikError(f"no trained model (run `nnik run {args.scenario}` first)", str(out))
    trained = load_scenario_of(out)
    if scn is None:
        _lock_job_dir(args, out)
        return out, trained
    if trained.fingerprint != scn.fingerprint:
        same = "a changed machine of the same name" if trained.name == scn.name else f"machine {scn.name!r}"
        raise NnikError(f"{args.scenario} describes {same}, but {out} holds a model of machine {trained.name!r} "
                        f"(trained from {trained.source}); give the model's own scenario, or `nnik run` this one first",
                        args.scenario)
    changed = [t for t in ("motion", "dynamics", "shaper", "tool") if scn.raw.get(t) != trained.raw.get(t)]
    if changed:
        console.print(f"{', '.join(f'[{t}]' for t in changed)} from {args.scenario}, changed since training (the "
                      "trained IK does not depend on them)", markup=False)
    _lock_job_dir(args, out)
    return out, scn


def _lock_job_dir(args, out: Path) -> None:
    if not args.check:  # it writes OUTDIR/job/: a directory, writable, one job at a time (the lock)
        check_job_outputs(check_model_dir(out, JOB_DIR), Path(args.job))


JOB_OUTPUTS = ("{}.json", "{}.png", "{}_precompensated.gcode", "{}_dynamics.png", "{}_chip_steps.csv")


def check_job_outputs(out: Path, job: Path) -> None:
    """The G-code file is never one of the files the job writes."""
    from nnik.files.output_path import same_file

    for pattern in JOB_OUTPUTS:
        dest = out / JOB_DIR / pattern.format(job.stem)
        if dest.exists() and same_file(dest, job):
            raise NnikError(f"is a file the job writes ({dest}); nnik never writes over its inputs, move the G-code "
                            "file elsewhere", str(job))


def print_gcode_summary(g: dict) -> None:
    console.print(f"flavour: {g['flavour']} ({g['flavour_evidence']})")
    console.print(f"tool: {g['tool']}, rule {g['tool_rule']} ({g['tool_rule_why']}): {g['moves_tool_on']} tool-on "
                  f"moves, {g['moves_tool_off']} tool-off moves")
    if g["extent_mm"]:
        (x0, y0), (x1, y1) = g["extent_mm"]
        console.print(f"extent: X {x0:g}..{x1:g} Y {y0:g}..{y1:g} mm from the work origin; frame {g['frame']}")
    if g["tool"] == "laser" and g["z_range_mm"][0] != g["z_range_mm"][1]:
        console.print(f"Z (the laser's focus): {g['z_range_mm'][0]:g}..{g['z_range_mm'][1]:g} mm")
    noted = ", ".join(f"{k} x{v}" for k, v in g["noted"].items())
    extra = [f"$ lines x{g['dollar_lines']} (the sender's)" if g["dollar_lines"] else "",
             f"words that replaced one of their modal group x{g['last_word_wins']}" if g["last_word_wins"] else ""]
    text = ", ".join(t for t in [noted, *extra] if t)
    console.print(f"noted (no effect on this machine): {text or 'nothing'}")


def behind_message(chip: dict, res: dict) -> str:
    """The simulated chip had not finished when its simulated-time bound ran out."""
    from nnik.firmware.gcode.chip import CLOCK_HZ

    period = CLOCK_HZ / res["motion"]["sample_hz"]
    per = chip.get("cycles_per_sample") or {}
    lines = res["gcode"]["lines_sent"]
    load = (f"; its sample loop took {per['mean']:.0f} cycles a sample on average, the sample period is "
            f"{period:.0f}") if per.get("mean") else ""
    return (f"the simulated chip had not finished after {chip['end_cycle'] / CLOCK_HZ:.0f} s of simulated time "
            f"(the plan takes {res['seconds']:.0f} s; {len(chip['replies'])} of {lines} lines answered): it falls "
            f"behind the plan{load}; lower the feed or [motion] sample_hz, or run the job with fewer, longer lines")


def cmd_job(args) -> dict:
    from nnik.firmware.gcode.job_input import JobOptions
    from nnik.firmware.model_dir import ModelDir
    from nnik.job.open_loop import run_job

    from nnik.commands.servo_job import cmd_servo_job, servo_target

    if (target := servo_target(args)) is not None:  # a dc_servo xy_table: the job closed loop
        if not args.check:
            check_job_outputs(check_model_dir(target[0], JOB_DIR), Path(args.job))
        return cmd_servo_job(args, target)
    if args.controller:
        raise NnikError("only a dc_servo xy_table's job has a controller", None, "--controller")
    out, scn = _model_dir(args)
    from nnik.files.pick_state import require_deliverable

    st = require_deliverable(out, "job")  # the job runs the firmware: only the verified pick, never the MLP instead
    opts = JobOptions(flavour=args.flavour, tool=args.tool, tool_rule=args.tool_rule, tool_z_mm=args.tool_z, fit=args.fit,
                      scale=args.scale, offset=args.offset)
    res = run_job(out, Path(args.job), seg_um=args.seg_um, use_chip=False if args.no_chip else None,
                  shaper=args.shaper, precompensate=args.precompensate, opts=opts, check=args.check, mcu=args.mcu,
                  scenario=scn, warn=lambda w: print(f"nnik: warning: {w}", file=sys.stderr, flush=True),
                  model=ModelDir.load(out, st), protocol=args.protocol)
    if args.check:
        print_gcode_summary(res)
        c = res["check"]
        console.print(f"check: {res['lines']} lines, {c['blocks']} planner blocks, {c['motion_s']:.2f} s of motion "
                      f"(planned), tool on {c['tool_on_mm']:.1f} mm, travel {c['travel_mm']:.1f} mm")
        return res
    print_gcode_summary(res["gcode"])
    console.print(job_table(res))
    if res.get("dynamics"):
        from nnik.report.job_dynamics import print_methods

        print_methods(console, res)
    chip = res["chip"]
    if "not_run" not in chip:
        console.print(f"self-test on simavr: {chip['selftest']}")
        stream = chip.get("stream") or {}
        if stream:
            buf = f" within the {stream['rx_buffer_bytes']}-byte receive buffer" if stream["rx_buffer_bytes"] else ""
            console.print(f"sender: {stream['protocol']}{buf}, lines {stream['lines']} ({stream['bytes_sent']} B)")
        if chip.get("end_s") is not None:
            console.print(f"simulated chip: {chip['segments_started']} segments, idle at {chip['end_s']:.3f} s "
                          f"({chip['motion_s']:.3f} s of motion; the model's {res['seconds']:.3f} s)")
        if chip.get("state") == "timeout":  # the chip fell behind the plan: say so, not "steps differ"
            raise NnikError(behind_message(chip, res), res["job"])
        if not (chip["steps_equal"] and chip["replies_equal"] and chip["selftest_pass"]):
            raise NnikError("the simulated chip's steps or answers differ from the Python model", res["job"])
    console.print(f"plot: {res['png']}; figures: {Path(res['png']).with_suffix('.json')}")
    return res


def job_table(res: dict) -> Table:
    """The job's summary, one row per figure. Its cells are Text, never read as rich markup on any
    console: a scenario's table names in brackets ("- (no [dynamics])") are printed as they are."""
    from nnik.report.job_summary import JOB_HEADER, job_row

    t = Table(title=Text(f"G-code job {res['job']} on {res['scenario']} ({res['seconds']:.2f} s of motion)"))
    t.add_column("item")
    t.add_column("result")
    for h, v in zip(JOB_HEADER, job_row(res)):
        t.add_row(Text(h), Text(v))
    return t
