"""`nnik identify LOG.csv`: each DC-servo axis's speed model (K, tau) from a log of its excitation
(nnik.dynamics.servo: log_csv reads and checks the log, fit fits it, predict draws the prediction).

Prints per axis one line `x: K ... counts/s/V, tau ... s (95 % CI ... - ... s; K ... - ...)`, nnik's
estimate (the output-error fit, which the encoder's noise does not bias), its discrete transfer
function, the one fitted by recursive least squares (the seed's method, checked by batch least
squares) with its K and tau, and the scenario's [servo.x.identified] / [servo.y.identified] lines. Writes those lines to -o FILE
(default: beside the log, LOG.identified.toml) and the measured against predicted motion to
--png FILE (default: -o's name with .png)."""

from __future__ import annotations

from pathlib import Path

from nnik.commands import common_options as co, option_types as opt
from nnik.errors import NnikError

HELP = "identify each DC-servo axis's speed model (K counts/s/V, tau s) from a log of t,u_x,u_y,count_x,count_y"
SUPPLY = opt.Number(float, opt.between(0.1, 1000.0, " V"))


def register(sub) -> None:
    description = HELP[:1].upper() + HELP[1:] + ". " + __doc__.split("\n\n", 1)[1]
    p = co.add_command(sub, "identify", HELP, description, result=True)
    p.add_argument("log", metavar="LOG", type=opt.path,
                   help="the log CSV: header t,u_x,u_y,count_x,count_y (any order, more columns ignored); t in s "
                   "with a uniform step, u in volts held until the next sample, counts of the encoders")
    p.add_argument("--supply", type=SUPPLY, metavar="V",
                   help="the u columns are duty fractions in [-1, 1] (duty / DUTY_MAX, sign = direction), the "
                   "volts are duty * V (V the supply; then a duty saturated at every sample is refused)")
    p.add_argument("--counts8", action="store_true",
                   help="the counts are an 8-bit counter's readings (0..255, wrapping; the seed's rig): unwrap them "
                   "(each step taken as the signed 8-bit difference, so under 128 counts a sample)")
    co.add_output_file(p, "where the [servo.x.identified] and [servo.y.identified] lines are written, a scenario "
                       "fragment", "beside the log, LOG.identified.toml")
    p.add_argument("--png", metavar="FILE", type=opt.path,
                   help="draw the measured against the predicted motion here (a file; default: -o's name with .png)")
    p.set_defaults(func=run)


def axis_line(f) -> str:
    m = f.model
    return (f"{f.axis}: K {m.k_counts_s_v:.5g} counts/s/V, tau {m.tau_s:.4g} s (95 % CI {m.tau_ci[0]:.4g} – "
            f"{m.tau_ci[1]:.4g} s; K {m.k_ci[0]:.5g} – {m.k_ci[1]:.5g} counts/s/V)")


def scenario_text(fits, src: str) -> str:
    head = [f"# nnik identify {Path(src).name}: each axis's speed model (K counts/s/V, tau s)"]
    return "\n".join(head + [f.model.scenario_lines(f.axis) for f in fits])


def _result(fits, log) -> dict:
    return {"tick_s": log.tick_s, "samples": len(log.t), "axes": {f.axis: {
        "k_counts_s_v": f.model.k_counts_s_v, "tau_s": f.model.tau_s, "k_ci": list(f.model.k_ci),
        "tau_ci": list(f.model.tau_ci), "coulomb_v": f.coulomb_v, "speed_fit": f.speed_fit,
        "discrete_num": list(f.discrete.num), "discrete_den": list(f.discrete.den),
        "rls": {"k_counts_s_v": f.k_rls, "tau_s": f.tau_rls_s}} for f in fits}}


def run(args) -> dict:
    import numpy as np

    from nnik.dynamics.servo.fit import fit_log
    from nnik.dynamics.servo.log_csv import read_servo_log
    from nnik.dynamics.servo.predict import predict_counts
    from nnik.dynamics.servo.servo_error import ServoError
    from nnik.files.atomic_write import write_file_atomic
    from nnik.files.output_path import check_output_file

    src = Path(args.log)
    out = Path(args.output) if args.output else src.with_name(src.stem + ".identified.toml")
    png = Path(args.png) if args.png else out.with_suffix(".png")
    check_output_file(out, [src], "the scenario lines")
    check_output_file(png, [src], "the picture")
    if png.absolute() == out.absolute():
        raise NnikError("--png and -o name the same file; the picture and the scenario lines need two", str(png))
    try:
        log = read_servo_log(src, args.supply, args.counts8)
        fits = fit_log(log)
    except ServoError as exc:
        raise NnikError(str(exc), str(src)) from None
    print(f"{src}: {len(log.t)} samples, tick {log.tick_s * 1000:.4g} ms ({log.t[-1] - log.t[0]:.4g} s)")
    for f in fits:
        print(axis_line(f))
        print(f"   discrete model: {f.model.discrete(log.tick_s).describe()}")
        print(f"   by RLS (the seed's method; batch LS agrees): {f.discrete.describe()}")
        print(f"     = K {f.k_rls:.5g} counts/s/V, tau {f.tau_rls_s:.4g} s (equation error: the encoder's noise biases "
              "tau short)")
        print(f"   output-error fit: Coulomb friction {f.coulomb_v:.3g} V, speed fit {100 * f.speed_fit:.1f} %")
    text = scenario_text(fits, str(src))
    print(text, end="")
    write_file_atomic(out, text)
    print(f"wrote {out}")
    pred = np.column_stack([predict_counts(log.volts[:, i], log.counts[0, i], f.model.k_counts_s_v, f.model.tau_s,
                                           f.coulomb_v, log.tick_s) for i, f in enumerate(fits)])
    from nnik.report.identify_png import identify_png

    labels = tuple(f"K {f.model.k_counts_s_v:.4g} counts/s/V, tau {f.model.tau_s:.4g} s, Coulomb {f.coulomb_v:.2g} V"
                   for f in fits)
    identify_png(png, f"nnik identify {src.name}: measured and predicted", log.t, log.counts, pred, labels)
    print(f"drew {png}")
    return _result(fits, log)
