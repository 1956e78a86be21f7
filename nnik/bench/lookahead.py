"""`make bench`, the planner against the float grbl oracle (nnik.bench.planner_oracle; measured as
nnik.bench.planner_compare states):

* the lookahead's cost on short-chord jobs: a 5 mm radius circle in chords of 0.01-0.2 mm at
  3000 mm/min, 1000 mm/s^2, for queues of 8, 15 and 16 blocks and each chip's default depth (the
  Uno's and the Mega's, unshaped: nnik.machine.ranges.plan_blocks_for, printed side by side): the
  integer planner's job time against the float planner with the same queue and with unlimited
  lookahead, and the float planner's own finite / unlimited ratio;
* the junction speed and acceleration ratios (integer / grbl's float limit) over random paths
  with random limits (corners, chords, arcs, reversals), and the job-time ratios: against the
  float planner with the same queue, continuous (nnik.bench.planner_oracle: a block joins the
  lookahead the instant the head leaves one) and on the chip's sample clock
  (nnik.bench.planner_sampled: the queue moves on between samples, as the chip's does).
Figures go to build/bench/lookahead.json too."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from nnik.bench import planner_oracle as oracle
from nnik.bench import planner_sampled
from nnik.bench.planner_compare import compare
from nnik.bench.planner_paths import chord_ops, path_ops, random_pieces
from nnik.firmware.config import MachineConfig
from nnik.machine.ranges import plan_blocks_for

OUT = Path("build") / "bench"
CHORDS_UM = (10, 20, 50, 100, 150, 200)
CHIPS = {"Uno": plan_blocks_for("atmega328p", 0), "Mega": plan_blocks_for("atmega2560", 0)}
QUEUES = tuple(sorted({8, 15, 16, *CHIPS.values()}))


def chord_table() -> list[dict]:
    rows = []
    for chord in CHORDS_UM:
        for n in QUEUES:
            cfg = MachineConfig(origin_um=(0, 0), plan_blocks=n)
            ops = chord_ops(chord, 5000, 1.0, 3_000_000)
            r = compare(ops, cfg)
            t_inf = oracle.plan(ops, cfg, None).time_s
            t_clock = planner_sampled.plan_time(ops, cfg)
            rows.append({"chord_um": chord, "blocks": n, "int_s": r["time_int_s"], "float_same_s": r["time_float_s"],
                         "float_unlimited_s": t_inf, "int_vs_float_same": r["time_ratio"],
                         "float_clock_s": t_clock, "int_vs_float_clock": r["time_int_s"] / t_clock,
                         "int_vs_unlimited": r["time_int_s"] / t_inf, "float_same_vs_unlimited": r["time_float_s"] / t_inf})
    return rows


def random_case(seed: int) -> tuple[list[tuple], MachineConfig]:
    """One random path (nnik.bench.planner_paths.random_pieces) at the feed with random limits:
    500, 1000 or 2000 Hz, 100-5000 mm/s^2 an axis, 1-100 um junction deviation, 2-16 blocks."""
    rng = np.random.default_rng(seed)
    hz = int(rng.choice([500, 1000, 2000]))
    cfg = MachineConfig(origin_um=(0, 0), sample_hz=hz,
                        accel_um_s2=tuple(int(rng.integers(100, 5000)) * 1000 for _ in range(2)),
                        junction_dev_um=int(rng.integers(1, 100)), plan_blocks=int(rng.integers(2, 17)),
                        max_feed_um_min=min(int(rng.integers(600, 9000)), ((1 << 24) - 1) * 60 * hz // 65536 // 1000) * 1000)
    return path_ops(random_pieces(rng), cfg.max_feed_um_min), cfg


def time_against_the_clock(ops: list[tuple], cfg: MachineConfig, r: dict) -> dict:
    """The integer planner's job time against the float planner with the same queue on the chip's
    sample clock: ratio, and the samples over 1.02 times it."""
    t = planner_sampled.plan_time(ops, cfg)
    return {"ratio": r["time_int_s"] / t if t > 0 else 1.0,
            "over_2pct_samples": (r["time_int_s"] - 1.02 * t) * cfg.sample_hz}


def random_ratios(jobs: int, seed: int) -> dict:
    J, A, T, S, over = [], [], [], [], 0
    for k in range(jobs):
        ops, cfg = random_case(seed + k)
        r = compare(ops, cfg)
        J.append(r["junction"])
        A.append(r["accel"])
        T.append(r["time_ratio"])
        c = time_against_the_clock(ops, cfg, r)
        S.append(c["ratio"])
        over += c["over_2pct_samples"] > 3
    j, a = np.concatenate(J), np.concatenate(A)
    moving = j[j > 0]
    q = lambda x, p: float(np.percentile(x, p)) if x.size else 0.0  # noqa: E731
    return {"jobs": jobs, "junctions": int(j.size), "junction_max": float(j.max()), "junction_median": q(moving, 50),
            "junction_p99": q(j, 99), "junctions_above_limit": int((j > 1.0).sum()), "accel_max": float(a.max()),
            "accel_p99": q(a, 99), "samples_above_accel": int((a > 1.0).sum()),
            "time_ratio_min": float(min(T)), "time_ratio_median": float(np.median(T)), "time_ratio_max": float(max(T)),
            "time_above_2pct": int(sum(t > 1.02 for t in T)),
            "clock_ratio_min": float(min(S)), "clock_ratio_median": float(np.median(S)), "clock_ratio_max": float(max(S)),
            "clock_above_2pct": int(over)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.lookahead", description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=20, help="random paths for the ratio distribution")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    rows = chord_table()
    print("lookahead on a 5 mm circle in chords (3000 mm/min, 1000 mm/s^2): job time ratios")
    print(f"  {'chord':>6} {'blocks':>6} {'int/float same N':>17} {'int/float on clock':>19} {'int/unlimited':>14} {'float N/unlimited':>18}")
    for r in rows:
        print(f"  {r['chord_um']:>4}um {r['blocks']:>6} {r['int_vs_float_same']:>17.4f} {r['int_vs_float_clock']:>19.4f} {r['int_vs_unlimited']:>14.4f}"
              f" {r['float_same_vs_unlimited']:>18.4f}")
    print("each chip's default depth (unshaped): job time / unlimited lookahead")
    print(f"  {'chord':>6}" + "".join(f" {f'{c} ({n} blocks)':>16}" for c, n in CHIPS.items()))
    for chord in CHORDS_UM:
        got = {r["blocks"]: r["int_vs_unlimited"] for r in rows if r["chord_um"] == chord}
        print(f"  {chord:>4}um" + "".join(f" {got[n]:>16.4f}" for n in CHIPS.values()))
    rr = random_ratios(args.jobs, args.seed)
    print(f"random paths ({rr['jobs']} jobs, {rr['junctions']} junctions): junction / grbl limit max {rr['junction_max']:.4f}, "
          f"median {rr['junction_median']:.4f} ({rr['junctions_above_limit']} above 1); accel / limit max {rr['accel_max']:.4f} "
          f"({rr['samples_above_accel']} above 1); job time / float (same N) {rr['time_ratio_min']:.4f}.."
          f"{rr['time_ratio_max']:.4f}, median {rr['time_ratio_median']:.4f} ({rr['time_above_2pct']} above 1.02); on the "
          f"sample clock {rr['clock_ratio_min']:.4f}..{rr['clock_ratio_max']:.4f}, median {rr['clock_ratio_median']:.4f} "
          f"({rr['clock_above_2pct']} more than 3 samples above 1.02)")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "lookahead.json").write_text(json.dumps({"chords": rows, "chips": CHIPS, "random": rr}, indent=2) + "\n")
    return 1 if rr["junctions_above_limit"] or rr["samples_above_accel"] else 0


if __name__ == "__main__":
    sys.exit(main())
