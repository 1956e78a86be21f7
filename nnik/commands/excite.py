"""`nnik excite SCENARIO`: the seed's excitation for a DC-servo table, a square wave plus Gaussian
noise on both axes at once (nnik.dynamics.servo.excitation, excite_plan), with the noise's variance
read literally from the seed: sigma^2 = 0.3 x A, A the square's amplitude in volts.

The amplitude and period come from a step probe of the scenario's plant: A = half the supply
(lowered if the swing would leave half the stroke), half period 5 tau on X and 7 tau on Y. Writes
into -o DIR: duty.csv (t,duty_x,duty_y: the integer duties, +-duty_max), log.csv (the scenario's
plant driven by them, in the log format `nnik identify` reads: t,u_x,u_y,count_x,count_y in s,
volts, counts), nnik_excite_duties.h (the duties as a PROGMEM table) and the firmware build that
plays them on the Uno: the Arduino library nnik_<scenario>_excite/ with the sketch
examples/<scenario>_excite/ and its arduino-mk Makefile (nnik.firmware.servo.excite_export), which
logs every tick over serial (115200 baud) in the format `nnik identify LOG --supply V` reads."""

from __future__ import annotations

import re
from pathlib import Path

from nnik.commands import common_options as co, option_types as opt
from nnik.errors import NnikError

HELP = ("write the seed's identification excitation for a DC-servo table: a square wave plus Gaussian noise "
        "of variance sigma^2 = 0.3 x A, A the square's amplitude in volts (the seed's \"variance 30 per cent of the "
        "amplitude\", read literally)")
SECONDS = opt.Number(float, opt.between(1.0, 600.0, " s"))
MARKER = ".nnik-excite"
MAX_TABLE_BYTES = 24 * 1024  # the duty table in the Uno's 32 KiB of flash, beside the servo runtime


def register(sub) -> None:
    description = HELP[:1].upper() + HELP[1:] + ". " + __doc__.split("\n\n", 1)[1]
    p = co.add_command(sub, "excite", HELP, description)
    p.add_argument("scenario", metavar="SCENARIO", help="a DC-servo scenario (a [servo] table, e.g. datasets/xy_table.toml)")
    co.add_outdir(p, "where duty.csv, log.csv and nnik_excite_duties.h are written", "excite_<scenario name>")
    p.add_argument("--seconds", type=SECONDS, default=20.0,
                   help="how long the excitation runs (default 20; the duty table must fit 24 KiB of the Uno's flash: "
                   "4 bytes a tick)")
    co.add_seed(p, "the excitation's Gaussian noise", "duties and log")
    p.set_defaults(func=run)


def duty_csv(tick_s: float, duty) -> str:
    rows = [f"{k * tick_s:.6f},{d[0]},{d[1]}" for k, d in enumerate(duty.tolist())]
    return "\n".join(["t,duty_x,duty_y", *rows]) + "\n"


def log_csv(tick_s: float, supply_v: float, duty_max: int, duty, counts) -> str:
    rows = [f"{k * tick_s:.6f},{d[0] * supply_v / duty_max:.6g},{d[1] * supply_v / duty_max:.6g},{c[0]},{c[1]}"
            for k, (d, c) in enumerate(zip(duty.tolist(), counts.tolist()))]
    return "\n".join(["t,u_x,u_y,count_x,count_y", *rows]) + "\n"


def c_header(ex, cfg, seed: int, source: str) -> str:
    n = len(ex.duty)
    body = ",\n".join("    {%d, %d}" % (d[0], d[1]) for d in ex.duty.tolist())
    axes = "; ".join(f"{n_}: A {a.amplitude_v:g} V, half period {a.half_period_ticks} ticks, sigma {a.sigma_v:.3g} V"
                     for n_, a in zip("XY", ex.axes))
    return f"""/* nnik excite {source} --seed {seed}: the seed's excitation, a square wave plus Gaussian noise
 * (sigma^2 = 0.3 x A volts), both axes at once. {axes}.
 * One row a tick ({cfg.tick_s * 1000:g} ms): the signed duty of X and Y, +-{cfg.duty_max} (sign = DIR). */
#ifndef NNIK_EXCITE_DUTIES_H
#define NNIK_EXCITE_DUTIES_H
#include <stdint.h>
#include <avr/pgmspace.h>

#define NNIK_EXCITE_TICKS {n}
#define NNIK_EXCITE_TICK_US {round(cfg.tick_s * 1e6)}UL
#ifndef NNIK_DUTY_MAX
#define NNIK_DUTY_MAX {cfg.duty_max}
#endif
#define NNIK_EXCITE_START_X {ex.start_counts[0]}L
#define NNIK_EXCITE_START_Y {ex.start_counts[1]}L

const int16_t nnik_excite_duties[NNIK_EXCITE_TICKS][2] PROGMEM = {{
{body}
}};

#endif
"""


def run(args) -> None:
    from nnik.dynamics.servo.excite_plan import excite
    from nnik.dynamics.servo.servo_error import ServoError
    from nnik.files.atomic_write import write_file_atomic
    from nnik.files.replace_dir import staged_folder
    from nnik.firmware.servo.excite_export import check_serial_rate, serial_log, tick_us, write_excite_library
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(args.scenario)
    cfg = getattr(scn, "servo", None)
    if cfg is None:
        raise NnikError("has no [servo] table: nnik excite drives a DC-servo table's plant", args.scenario)
    ticks = int(round(args.seconds / cfg.tick_s))
    tick_us(cfg.tick_s)
    if 4 * ticks > MAX_TABLE_BYTES:
        raise NnikError(f"{args.seconds:g} s is {ticks} ticks, a {4 * ticks}-byte duty table: more than the "
                        f"{MAX_TABLE_BYTES} bytes of flash it may take; give fewer --seconds", None, "--seconds")
    out = Path(args.outdir) if args.outdir else Path(f"excite_{Path(args.scenario).stem}")
    ws = scn.workspace
    try:
        ex = excite(cfg, tuple((lo * 1000.0, hi * 1000.0) for lo, hi in (ws.x_mm, ws.y_mm)), args.seconds, args.seed)
    except ServoError as exc:
        raise NnikError(str(exc), args.scenario) from None
    for name, a, p in zip("xy", ex.axes, ex.probes):
        print(f"{name}: step probe K {p.k_counts_s_v:.4g} counts/s/V, tau {p.tau_s:.4g} s -> square +-{a.amplitude_v:g} V, "
              f"half period {a.half_period_ticks} ticks ({a.half_period_ticks * cfg.tick_s:g} s), noise sigma "
              f"{a.sigma_v:.3g} V (sigma^2 = 0.3 x {a.amplitude_v:g})")
    check_serial_rate(serial_log(ex.duty, ex.counts, cfg.tick_s, cfg.duty_max), cfg.tick_s)
    name = re.sub(r"\W", "_", Path(args.scenario).stem)
    files = {"duty.csv": duty_csv(cfg.tick_s, ex.duty),
             "log.csv": log_csv(cfg.tick_s, cfg.supply_v, cfg.duty_max, ex.duty, ex.counts),
             "nnik_excite_duties.h": c_header(ex, cfg, args.seed, Path(args.scenario).name)}
    with staged_folder(out, MARKER, "excitation folder", f"nnik excite {args.scenario} --seed {args.seed}\n") as tmp:
        for fname, text in files.items():
            write_file_atomic(tmp / fname, text)
        lib = write_excite_library(tmp / f"nnik_{name}_excite", cfg, files["nnik_excite_duties.h"], ticks,
                                   ex.start_counts, name, f"nnik excite {Path(args.scenario).name} --seed {args.seed}")
    span = [f"{name} {ex.table_um[:, i].min() / 1000:.2f}..{ex.table_um[:, i].max() / 1000:.2f} mm"
            for i, name in enumerate("xy")]
    print(f"wrote {out}/: {', '.join(files)} ({ticks} ticks; the table stays within {', '.join(span)})")
    print(f"firmware: {out}/{lib['libname']}/examples/{lib['example']} (make, then make upload; log its serial output "
          f"at 115200 baud and run nnik identify LOG --supply {cfg.supply_v:g})")
