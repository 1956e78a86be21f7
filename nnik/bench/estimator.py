"""The MLP estimator's full search-space check (CI measures a sample: tests/bench/mlp_cost/
test_search_check.py): random networks `nnik search` proposes, every tanh replacement, int8
and int16, full / residual / DAC, on avr-gcc -Os and -O2 (simavr) and SDCC pic16 (gpsim; the
networks SDCC builds in reasonable time), predicted vs measured, each within the band its
estimate states.  ``--record`` stores the bands (nnik.bench.mlp_cost.search_check.record).

    python3 -m nnik.bench.estimator [-n 60] [--seed 31] [--record]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from nnik.bench.mlp_cost import search_check as sc
from nnik.implementations.mlp.cost.coverage import measurable
from nnik.implementations.mlp.cost.synthetic import synthetic_model

PROFILES = ("avr-gcc-Os", "avr-gcc-O2", "pic18-sdcc")


def run(n: int, seed: int, profiles=PROFILES, workdir: Path | None = None, verbose: bool = True) -> list[dict]:
    specs = sc.draw_specs(n, seed)
    rows = []
    with tempfile.TemporaryDirectory(prefix="nnik-estimator-") as tmp:
        wd = Path(workdir or tmp)
        for prof in profiles:
            target = "pic18" if prof.startswith("pic18") else "avr"
            mine = [sp for sp in specs if measurable(sp, synthetic_model(sp, kernel=sc.KERNEL), target)]
            rows += sc.check(mine, [prof], n_vec=40, workdir=wd, verbose=verbose)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m nnik.bench.estimator", description=__doc__.split("\n\n")[0])
    ap.add_argument("-n", type=int, default=60)
    ap.add_argument("--seed", type=int, default=31)
    ap.add_argument("--profile", action="append", help=f"default: {', '.join(PROFILES)}")
    ap.add_argument("--record", action="store_true", help="store each profile's band in its calibration file")
    a = ap.parse_args(argv)
    rows = run(a.n, a.seed, tuple(a.profile or PROFILES))
    bad = 0
    for prof in a.profile or PROFILES:
        rr = [r for r in rows if r["profile"] == prof]
        errs = [r["cycles_err_pct"] for r in rr]
        out = [r for r in rr if r["stated_pct"] is None or abs(r["cycles_err_pct"]) > r["stated_pct"]]
        bad += len(out)
        print(f"{prof:11s} {len(rr):3d} networks  error {min(errs):+.2f} .. {max(errs):+.2f} %  "
              f"outside the stated band: {len(out)}")
    if a.record:
        for prof, s in sc.record(rows, a.seed).items():
            print(f"{prof}: recorded ±{s['stated_cycles_err_pct']} % ({s['networks']} networks)")
    return 1 if bad and not a.record else 0


if __name__ == "__main__":
    sys.exit(main())
