"""Arcs planned as one block (nnik.firmware.gcode.planner_arc) against arcs planned as their chords
(one line block each, grbl's way), by job time: the integer planner's samples (the firmware's
model, bit for bit its sampler) and the float oracle's (nnik.bench.planner_oracle), with the same
limits and queue.  On the CAM jobs of the real corpus (datasets/jobs/, the ones with G2/G3, at the
default seg_um and at 100 um chords) and on random CAM-like paths (arcs of 0.2-20 mm radius in
0.01-0.2 mm chords, corners, reversals).  Prints each ratio chords / arc blocks (above 1: arc
blocks are faster).

    python3 -m nnik.bench.arc_blocks [--seed N] [--paths N]
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from nnik.bench import planner_oracle as oracle
from nnik.bench.planner_paths import arc_block_ops, path_ops, random_pieces
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.interpreter import run_lines
from nnik.firmware.gcode.sampler import run_arrays

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"


def job_seconds(ops: list[tuple], cfg: MachineConfig) -> tuple[float, float]:
    """(integer planner's motion time, float oracle's), s: the samples (rests excluded) / rate."""
    a = run_arrays(ops, cfg)
    return float((a.kind == 0).sum()) / cfg.sample_hz, oracle.plan(ops, cfg).time_s


def arc_jobs() -> list[Path]:
    """The corpus' jobs that hold an arc (G2 or G3)."""
    out = []
    for p in sorted(JOBS.glob("*.gcode")):
        words = p.read_text().upper().replace("G02", "G2").replace("G03", "G3").split()
        if any(w in ("G2", "G3") for w in words):
            out.append(p)
    return out


def job_ratios(path: Path, cfg: MachineConfig) -> dict:
    lines = path.read_text().splitlines()
    res = {}
    for ab in (False, True):
        c = dataclasses.replace(cfg, arc_blocks=ab)
        ops = run_lines(lines, c).plan.ops
        res[ab] = (job_seconds(ops, c), sum(op[0] in ("push", "arc") for op in ops))
    (ti0, tf0), n0 = res[False]
    (ti1, tf1), n1 = res[True]
    return {"blocks": (n0, n1), "int": ti0 / ti1, "float": tf0 / tf1, "int_s": (ti0, ti1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=26)
    ap.add_argument("--paths", type=int, default=12)
    args = ap.parse_args(argv)
    print("arc blocks vs chord blocks: job time ratio chords / arcs (> 1: arc blocks faster)")
    for seg in (500, 100):
        cfg = MachineConfig(origin_um=(0, 0), seg_um=seg)
        print(f"corpus, seg_um {seg}, lookahead {cfg.lookahead}, 1 kHz:")
        for p in arc_jobs():
            r = job_ratios(p, cfg)
            print(f"  {p.stem:22s} blocks {r['blocks'][0]:5d} -> {r['blocks'][1]:5d}  integer {r['int']:.3f} "
                  f"({r['int_s'][0]:.2f} s -> {r['int_s'][1]:.2f} s)  float {r['float']:.3f}")
    rng = np.random.default_rng(args.seed)
    cfg = MachineConfig(origin_um=(0, 0), plan_blocks=8)
    ri, rf = [], []
    for _ in range(args.paths):
        pieces = random_pieces(rng, 20)
        feed = cfg.max_feed_um_min
        a, b = path_ops(pieces, feed), arc_block_ops(pieces, feed, cfg)
        (ti0, tf0), (ti1, tf1) = job_seconds(a, cfg), job_seconds(b, cfg)
        ri.append(ti0 / ti1)
        rf.append(tf0 / tf1)
    print(f"random CAM paths ({args.paths}, 0.01-0.2 mm chords, lookahead 8): integer median {np.median(ri):.3f} "
          f"(min {min(ri):.3f}, max {max(ri):.3f}), float median {np.median(rf):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
