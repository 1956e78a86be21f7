"""Calibrate the cost model of poly's wide path (nnik.implementations.poly.wide_cost) on simavr
and gpsim, and write nnik/calibration/poly32.json.

Configurations are drawn as `nnik search` draws them (nnik.bench.costs.draw_config) on every
shipped scenario and on random machines; each is fitted, built and measured on both chips. The
fit is judged by its leave-one-out error; the band an estimate states is recorded separately, by
``python3 -m nnik.bench.costs --kinds poly32 --record`` on draws the fit did not see.

    python3 -m nnik.bench.poly32_calibration [--per-scenario 3] [--machines 5] [--seed 77]
    python3 -m nnik.bench.poly32_calibration --refit ROWS.json   (refit stored measurements)
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from nnik.bench import costs
from nnik.implementations.poly import wide_cost
from nnik.implementations.poly.wide import CALIBRATION

TARGETS = ("avr", "pic18")
LOO_TOLERANCE_PCT = 3.0  # leave-one-out error that counts as validated


def measure(problems: dict, per_problem: int, seed: int, workdir: Path, say=print) -> list[dict]:
    from nnik.implementations.verify import verify_on_target

    rows = []
    for pi, (label, problem) in enumerate(problems.items()):
        rng = np.random.default_rng([seed, pi])
        for n in range(per_problem):
            fam, cfg = costs.draw_config(problem, "poly32", rng)
            impl = costs.fit(problem, fam, cfg)
            row = {"scenario": label, "config": cfg}
            for t in TARGETS:
                r = verify_on_target(impl, t, workdir / f"{label}-{n}" / "c", workdir / f"{label}-{n}" / t, n_inside=40)
                if "not_run" in r or not r["bit_exact"]:
                    raise SystemExit(f"{label} {cfg} on {t}: {r.get('not_run') or 'not bit-exact'}")
                row[t] = {**wide_cost.counts(impl, t), "cycles": float(r["cycles"]), "flash_bytes": int(r["flash_bytes"])}
            say(json.dumps(row))
            rows.append(row)
    return rows


def leave_one_out_pct(rows: list[dict], target: str) -> float:
    worst = 0.0
    for i in range(len(rows)):
        cal = wide_cost.fit(rows[:i] + rows[i + 1:], target)
        r = rows[i][target]
        worst = max(worst, abs(100 * (wide_cost.predict(cal["cycles"], r, wide_cost.FEATURES[target], r["known"]) / r["cycles"] - 1)))
    return round(worst, 2)


def write(rows: list[dict], how: str) -> dict:
    """Fit every target's model on `rows` and write the calibration (keeping a recorded check)."""
    old = json.loads(CALIBRATION.read_text()) if CALIBRATION.exists() else {}
    targets = {t: wide_cost.fit([r for r in rows if t in r], t) for t in TARGETS}
    loo = {t: leave_one_out_pct([r for r in rows if t in r], t) for t in TARGETS}
    cal = {"targets": targets, "features": wide_cost.FEATURES, "loo_max_abs_pct": loo,
           "validated": bool(max(loo.values()) <= LOO_TOLERANCE_PCT), "how": how, "measurements": rows}
    if "check" in old:
        cal["check"] = old["check"]
    CALIBRATION.write_text(json.dumps(cal, indent=1) + "\n")
    return cal


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m nnik.bench.poly32_calibration", description=__doc__.split("\n\n")[0])
    ap.add_argument("--per-scenario", type=int, default=3)
    ap.add_argument("--machines", type=int, default=5)
    ap.add_argument("--seed", type=int, default=77)
    ap.add_argument("--refit", type=Path, help="refit the measurement rows stored in this JSON file")
    a = ap.parse_args(argv)
    if a.refit:
        rows = json.loads(a.refit.read_text())
        how = f"python3 -m nnik.bench.poly32_calibration --refit ({len(rows)} measured configurations)"
    else:
        with tempfile.TemporaryDirectory(prefix="nnik-poly32-") as tmp:
            problems = {s: costs.problem_of(costs.DATASETS / f"{s}.toml") for s in costs.SCENARIOS}
            problems.update(costs.random_problems(a.machines, a.seed, Path(tmp) / "machines"))
            rows = measure(problems, a.per_scenario, a.seed, Path(tmp))
        how = f"python3 -m nnik.bench.poly32_calibration --per-scenario {a.per_scenario} --machines {a.machines} --seed {a.seed}"
    cal = write(rows, how)
    print(f"wrote {CALIBRATION}: leave-one-out max |error| {cal['loo_max_abs_pct']} % ({len(rows)} configurations)")
    return 0 if cal["validated"] else 1


if __name__ == "__main__":
    sys.exit(main())
