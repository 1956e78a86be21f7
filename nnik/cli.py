"""The `nnik` command line: the parser built from nnik/commands/ (one module per command or task
group) and the one place where errors become one `nnik: error:` line and exit 2."""

from __future__ import annotations

import argparse
import sys
import warnings

from nnik.commands import common_options as co, option_types as opt
from nnik.errors import NnikError, NnikWarning, warning_line
from nnik.files.atomic_write import reraise_lost_interrupts
from nnik.files.os_errors import behind, os_error_line
from nnik.files.outdir import release_locks

DESCRIPTION = (
    "Inverse kinematics as verified fixed-point C for 8-bit MCUs. Every implementation family (mlp, poly, lut, "
    "hybrid) is fitted to a scenario on one contract, each family's best is verified bit for bit on the host and on "
    "simulated chips (AVR: avr-gcc + simavr; PIC18: SDCC + gpsim), and the cheapest that meets the scenario's "
    "[target] is the pick, c/NAME.c; G-code jobs then run through it on the simulated chip.")
EPILOG = """commands by task:
  start here          run, job
  the pick            select, search, verify, report, export --arduino
  the MLP alone       generate, train, evaluate, export, estimate, tanh
  measured machines   synth-csv, shaper-calibrate
  DC servos           excite, identify

`nnik COMMAND --help` says what each one reads and writes."""


def build_parser() -> argparse.ArgumentParser:
    from nnik.commands import (estimate, excite, export, identify, job, mlp_steps, report, run, search, select,
                               shaper_calibrate, synth_csv, tanh, verify)

    ap = opt.OneLineParser(prog="nnik", description=DESCRIPTION, epilog=EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in (run, job, select, search, verify, report, export, mlp_steps, estimate, tanh, synth_csv,
                   shaper_calibrate, excite, identify):
        module.register(sub)
    opt.check_paths(ap)
    return ap


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:  # a second Ctrl-C, or one between the command and its clean-up
        print("nnik: interrupted", file=sys.stderr)
        return 130


def _main(argv: list[str] | None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help (0), or a bad option: the one line was printed (2)
        return exc.code if isinstance(exc.code, int) else 2
    reraise_lost_interrupts()
    # numpy's RuntimeWarnings are held back: after an error the one error line is all that shows;
    # after success they follow the output, one line each, so nothing is lost.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        warnings.simplefilter("always", NnikWarning)
        try:
            with co.quiet_stdout(args):
                result = args.func(args)
        except NnikError as exc:
            print(f"nnik: error: {exc}", file=sys.stderr)
            return 2
        except OSError as exc:  # a full disk, a read-only place: one line (what nnik trusts is written atomically)
            print(f"nnik: error: {os_error_line(exc)}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            print("nnik: interrupted", file=sys.stderr)
            return 130
        except Exception as exc:  # a Ctrl-C that a library's clean-up turned into its own error
            if behind(exc, KeyboardInterrupt) is None:  # numpy's zip writer, for one
                raise
            print("nnik: interrupted", file=sys.stderr)
            return 130
        finally:
            release_locks()
    if getattr(args, "json", False):
        print(co.json_text(result))
    for w in {(str(w.message), w.filename, w.lineno): w for w in caught}.values():
        print(warning_line(w), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
