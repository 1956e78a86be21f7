"""Command line: python3 -m nnik.bench.mlp_cost {calibrate,sweep,search-check,model}."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from nnik.errors import NnikError
from nnik.bench.mlp_cost.calibrate import calibrate
from nnik.implementations.mlp.cost.predict import estimate, format_estimate, load_integer_model
from nnik.implementations.mlp.cost.calibrations import BUILTIN_PROFILES, TARGETS, profiles, resolve_profile
from nnik.bench.mlp_cost.sweep import SWEEP_ARCHS, SWEEP_TANH, format_sweep, sweep


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m nnik.bench.mlp_cost", description="static cycle/flash/RAM estimator")
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("calibrate", help="run the microbenchmarks on the simulators, write nnik/calibration/*.json")
    c.add_argument("--target", choices=TARGETS, action="append", help="default: both")
    c.add_argument("--profile", help="one profile (default: every profile of the target)")
    c.add_argument("--kernel", action="append", help="kernel(s) to calibrate (default: every kernel offered)")
    c.add_argument("--refit", action="store_true", help="re-fit the measurements of the last run (no simulator)")
    s = sub.add_parser("sweep", help="trained networks, hidden sizes 4-16: predicted vs measured")
    s.add_argument("--target", choices=TARGETS, action="append", help="default: both")
    s.add_argument("--record", action="store_true", help="store the summary in the calibration files")
    s.add_argument("--quick", action="store_true", help="4 architectures only")
    s.add_argument("--kernel", help="quantise for this kernel (default: the quantiser's default)")
    s.add_argument("--tanh", action="append", help=f"tanh variant(s) (default: {', '.join(SWEEP_TANH)}; "
                   "'' = the kernel's own table)")
    s.add_argument("--profile", action="append", help="only these profiles")
    s.add_argument("--arch", action="append", help="hidden sizes, e.g. 8 or 8,8 (repeatable; default: the sweep set)")
    k = sub.add_parser("search-check", help="random MLPs of the search space (fast kernel): predicted vs measured")
    k.add_argument("-n", type=int, default=12, help="architectures to draw (default 12)")
    k.add_argument("--seed", type=int, default=19)
    k.add_argument("--depth", type=int, action="append", choices=(1, 2), help="hidden layers to draw (default 1 and 2)")
    k.add_argument("--profile", action="append", help="profiles (default: avr-gcc-Os, pic18-sdcc)")
    k.add_argument("--record", action="store_true", help="store each profile's stated error in its calibration file")
    k.add_argument("--validated-only", action="store_true",
                   help="measure only the networks whose estimate is validated (PIC18: no SDCC build of a large C path)")
    m = sub.add_parser("model", help="estimate a trained model (OUTDIR or model.pt)")
    m.add_argument("model", type=Path)
    m.add_argument("--target", choices=TARGETS, default="avr")
    m.add_argument("--compiler", "--profile", dest="profile", help="profile, e.g. avr-gcc-O2 or O2")
    m.add_argument("--clock-hz", type=int, default=16_000_000)
    m.add_argument("--tanh", help="tanh variant (default: the scenario's)")
    m.add_argument("--kernel", help="kernel (default: the scenario's [export] kernel)")
    m.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    try:
        if args.cmd == "calibrate":
            for t in args.target or TARGETS:
                for prof in ([resolve_profile(t, args.profile)] if args.profile else
                             [p for p in profiles(t) if p in BUILTIN_PROFILES]):
                    calibrate(t, prof, kernels=args.kernel, refit=args.refit)
        elif args.cmd == "sweep":
            archs = ((4,), (10,), (16,), (8, 8)) if args.quick else SWEEP_ARCHS
            if args.arch:
                archs = tuple(tuple(int(h) for h in a.split(",")) for a in args.arch)
            rows = sweep(tuple(args.target or TARGETS), archs=archs, record=args.record, kernel=args.kernel,
                         tanhs=tuple(args.tanh) if args.tanh else SWEEP_TANH, profiles_=args.profile)
            print(format_sweep(rows))
        elif args.cmd == "search-check":
            from nnik.bench.mlp_cost import search_check as sc

            specs = sc.draw_specs(args.n, args.seed, tuple(args.depth or (1, 2)))
            rows = sc.check(specs, args.profile or ["avr-gcc-Os", "pic18-sdcc"], only_validated=args.validated_only)
            print(json.dumps(sc.record(rows, args.seed) if args.record else rows, indent=1))
        else:
            im = load_integer_model(args.model, tanh=args.tanh, kernel=args.kernel)
            est = estimate(im, args.target, args.profile, args.clock_hz)
            print(json.dumps(est, indent=1) if args.json else format_estimate(est, im))
    except NnikError as exc:
        print(f"nnik estimate: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
