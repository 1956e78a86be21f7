"""`nnik shaper-calibrate LOG.csv`: the axis's resonance and the input shaper for it, from the log
of Klipper's resonance test (nnik.dynamics.resonance_log, nnik.dynamics.calibrate_log).

Prints `resonance: F Hz, damping Z` first, then each shaper's fit (frequency, vibration,
smoothing, max accel), the recommendation, and the scenario's [shaper] lines; writes those lines
to -o FILE and the picture to --png FILE (default: beside -o, FILE.png)."""

from __future__ import annotations

from pathlib import Path

from nnik.commands import common_options as co
from nnik.errors import NnikError

HELP = ("find an axis's resonance and the input shaper for it from Klipper's resonance test log "
        "(raw_data_<axis>_*.csv or resonances_<axis>_*.csv)")


def _zeta(text: str | None) -> float:
    from nnik.dynamics.shaper_figures import DEFAULT_ZETA

    if text is None:
        return DEFAULT_ZETA
    try:
        z = float(text)
    except ValueError:
        raise NnikError(f"--damping-ratio needs a number, not {text!r}", None, "--damping-ratio") from None
    if not 0 <= z <= 0.2:
        raise NnikError(f"--damping-ratio must be in [0, 0.2] (every shaper's design range), got {z:g}", None,
                        "--damping-ratio")
    return z


def register(sub) -> None:
    description = HELP[:1].upper() + HELP[1:] + ". " + __doc__.split("\n\n", 1)[1]
    p = co.add_command(sub, "shaper-calibrate", HELP, description)
    p.add_argument("log", metavar="LOG", help="Klipper's raw accelerometer CSV (#time,accel_x,accel_y,accel_z) or its PSD CSV "
                   "(freq,psd_x,psd_y,psd_z,psd_xyz)")
    p.add_argument("--axis", choices=("x", "y", "xy"), help="the axis the log tested (default: from the file name, "
                   "raw_data_x_... / resonances_y_...; else both)")
    p.add_argument("--damping-ratio", help="the damping ratio the shapers are designed "
                   "for (default 0.1, Klipper's)")
    co.add_output_file(p, "where the [shaper] lines are written too, a scenario fragment", "none, printed only")
    p.add_argument("--png", metavar="FILE", help="draw the PSD and each shaper's response here (a file; default: "
                   "-o's name with .png)")
    p.set_defaults(func=run)


def shaper_lines(axes: str, kind: str, freq: float, zeta: float, res) -> list[str]:
    out = [f"# nnik shaper-calibrate: resonance {res.f_hz:.1f} Hz, damping {res.zeta:.3f} "
           f"(for [dynamics]: f_hz = {res.f_hz:.1f}, zeta = {res.zeta:.3f})", "[shaper]"]
    for a in axes:
        out += [f'shaper_type_{a} = "{kind}"', f"shaper_freq_{a} = {freq:.1f}", f"damping_ratio_{a} = {zeta:g}"]
    return out


def run(args) -> None:
    from nnik.dynamics.calibrate import CalibrationError
    from nnik.dynamics.calibrate_log import calibrate
    from nnik.dynamics.resonance_log import read_log
    from nnik.files.atomic_write import write_file_atomic

    src = args.log
    zeta = _zeta(args.damping_ratio)
    out = Path(args.output) if args.output else None
    png = Path(args.png) if args.png else (out.with_suffix(".png") if out else None)
    for path, opt in ((out, "-o"), (png, "--png")):
        if path is not None and (path.is_dir() or not path.parent.is_dir()):
            raise NnikError(f"cannot write {path}: {'a directory' if path.is_dir() else 'no such directory'}", None, opt)
    try:
        log = read_log(src)
        axes = args.axis or log.axis or "xy"
        if axes not in ("x", "y", "xy"):
            raise CalibrationError(f"the file name says axis {axes!r}; nnik shapes X and Y: give --axis x or y")
        cal = calibrate(log, zeta)
    except CalibrationError as exc:
        raise NnikError(str(exc), src) from None
    res, best = cal.resonance, cal.best
    print(f"resonance: {res.f_hz:.1f} Hz, damping {res.zeta:.3f}")
    what = f"{len(log.rows)} samples at {cal.spectrum.rate_hz:.0f} Hz" if log.kind == "raw" else f"{len(log.rows)} PSD bins"
    print(f"from {src}: {what}, axis {axes}; fitted over {res.band[0]:.1f}-{res.band[1]:.1f} Hz "
          f"(peak of the response at {res.peak_hz:.1f} Hz)")
    print(f"shapers (damping ratio {cal.zeta:g}; Klipper's vibration, smoothing and max accel):")
    for kind, fit in cal.fits.items():
        print(f"  {kind:9s} {fit.freq_hz:6.1f} Hz  vibration {100 * fit.vibration:5.1f} %  smoothing "
              f"{fit.smoothing_mm:.3f} mm  max accel {round(fit.max_accel_mm_s2 / 100) * 100:>6,.0f} mm/s^2")
    print(f"recommended: {best.kind} at {best.freq_hz:.1f} Hz (vibration {100 * best.vibration:.1f} %, smoothing "
          f"{best.smoothing_mm:.3f} mm, max accel {round(best.max_accel_mm_s2 / 100) * 100:,.0f} mm/s^2)")
    lines = shaper_lines(axes, best.kind, best.freq_hz, cal.zeta, res)
    print("\n".join(lines))
    if out is not None:
        write_file_atomic(out, "\n".join(lines) + "\n")
        print(f"wrote {out}")
    if png is not None:
        from nnik.report.shaper_png import shaper_png

        shaper_png(png, Path(src).name, cal)
        print(f"drew {png}")
