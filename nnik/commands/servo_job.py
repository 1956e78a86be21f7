"""`nnik job` on a DC-servo xy_table: the job closed loop (nnik.job.closed_loop), its figures printed.

`nnik job OUTDIR JOB.gcode [--controller pid|pdff|ccc|nn_axes|nn_vector]` (OUTDIR: what `nnik run`
wrote for a dc_servo xy_table), or `nnik job SCENARIO.toml JOB.gcode [-o OUTDIR]`. Prints the
contour error (max and RMS, um), the tracking error per axis, the duty's saturation, a learning
controller's weight updates and clamps (diverged when the clamps pass 1 % of the updates), the
chip's cycles per tick and `mismatch N` (the ticks where the chip's duty, or its weights' checksum,
differs from the model's; exit 2 when N > 0).
"""

from __future__ import annotations

from pathlib import Path

from nnik.errors import NnikError

OPEN_LOOP_ONLY = ("shaper", "precompensate", "tool", "tool_rule", "tool_z")


def servo_target(args) -> tuple[Path, object] | None:
    """(OUTDIR, the scenario) when the job's machine is a dc_servo xy_table; None otherwise."""
    from nnik.job.servo_dir import is_servo_dir

    first = Path(args.scenario)
    if first.is_dir():
        return (first, None) if is_servo_dir(first) else None
    if first.suffix.lower() != ".toml" or not first.is_file():
        return None
    from nnik import pipeline
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(first)
    if scn.servo is None:
        return None
    return (Path(args.outdir) if args.outdir else pipeline.default_outdir(scn)), scn


def cmd_servo_job(args, target) -> dict:
    from nnik.firmware.gcode.job_input import JobOptions
    from nnik.job.closed_loop import ClosedLoopJob
    from nnik.job.parse import JobRequest
    from nnik.job.servo_dir import ServoDir

    for name in OPEN_LOOP_ONLY:
        if getattr(args, name, None):
            raise NnikError("an open-loop machine's option: a dc_servo xy_table's job has no shaper, precompensation "
                            "or tool", None, "--" + name.replace("_", "-"))
    out, scn = target
    model = ServoDir.load(out, scn)
    opts = JobOptions(flavour=args.flavour, fit=args.fit, scale=args.scale, offset=args.offset)
    req = JobRequest(Path(args.job), model.scenario, args.seg_um, None, False, opts)
    res = ClosedLoopJob(args.controller, False if args.no_chip else None, args.check).run(model, req)
    print_servo_job(res)
    chip = res.get("chip", {})
    if chip.get("mismatches"):
        raise NnikError(f"the chip's duty or weights differ from the model's at {chip['mismatches']} ticks", res["job"])
    return res


def print_servo_job(res: dict) -> None:
    r = res["reference"]
    print(f"closed-loop job {res['job']} on {res['scenario']}: {r['ticks']} ticks of {r['tick_s'] * 1e3:g} ms "
          f"({r['seconds']:.2f} s), {r['steps']} raw steps")
    if "controller" not in res:
        return
    c, t = res["contour_um"], res["tracking_um"]
    print(f"controller: {res['controller']}")
    print(f"contour error: max {c['max_um']:.1f} um, RMS {c['rms_um']:.1f} um")
    print(f"tracking error: x max {t['x']['max_um']:.1f} um RMS {t['x']['rms_um']:.1f} um, "
          f"y max {t['y']['max_um']:.1f} um RMS {t['y']['rms_um']:.1f} um")
    print(f"duty saturated: {res['saturated_fraction'] * 100:.1f} % of the ticks")
    for s in res["steps"]:
        settle = "not settled" if s["settling_s"] is None else f"settles in {s['settling_s']:.3f} s"
        print(f"step to X{s['to_mm'][0]:g} Y{s['to_mm'][1]:g} mm: overshoot {s['overshoot_um']:.1f} um, {settle} "
              f"(+-{s['settle_band_um']:.0f} um), steady-state error {s['steady_state_um']:.1f} um")
    lr = res.get("learning")
    if lr:
        print(f"learning: {lr['updates']} weight updates, {lr['clamps']} clamps ({lr['clamp_pct']:.2f} %): "
              + ("DIVERGED (clamps > 1 % of the updates)" if lr["diverged"] else "not diverged"))
    if res["reversals"]["count"]:
        print(f"at reversals ({res['reversals']['count']}): contour error max {res['reversals']['max_um']:.1f} um")
    chip = res["chip"]
    if "not_run" in chip:
        print(f"chip: not run ({chip['not_run']})")
    else:
        print(f"controller cycles per tick: max {chip['controller_cycles_max']}")
        print(f"cycles per tick, the tick and the encoder interrupts: max {chip['tick_cycles_max']} of "
              f"{chip['period_cycles']} ({chip['cpu_pct_max']:.1f} % CPU)")
        print(f"mismatch {chip['mismatches']}")
    print(f"plot: {res['png']}")
