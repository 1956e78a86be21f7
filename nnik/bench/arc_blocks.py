"""Arcs planned as one block (nnik.firmware.gcode.planner_arc) against arcs planned as their chords
(one line block each, grbl's way), by job time: the integer planner's samples (the firmware's
model, bit for bit its sampler) and the float oracle's (nnik.bench.planner_oracle), with the same
limits and queue.  On the CAM jobs of the real corpus (datasets/jobs/, the ones with G2/G3, at the
default seg_um and at 100 um chords) and on random CAM-like paths (arcs of 0.2-20 mm radius in
0.01-0.2 mm chords, corners, reversals).  Prints each ratio chords / arc blocks (above 1: arc
blocks are faster).  Then the sampled acceleration inside arcs, both ways: each sample's point
taken exactly on the chord polyline at the path length the samples moved, its second difference
per axis against that axis' limit (a line of 5 mm, an arc of 2-20 mm radius in 0.01-0.2 mm
chords, a line; the samples within 0.3 mm of the arc's ends left out).  Above 1 at the chord
ends: grbl's junction rule lets a vertex be passed with a jump in direction, and the chord ends
rounded to whole um kink the polygon more than the arc turns on short chords.

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


def polyline(ops: list[tuple]) -> np.ndarray:
    """The block ends and chord ends the ops go through, from (0, 0) (um)."""
    verts = [(0, 0)]
    for op in ops:
        if op[0] == "arc":
            verts += list(op[6])
        elif op[0] == "push":
            verts.append(op[1:3])
    return np.asarray(verts, float)


def exact_points(ops: list[tuple], cfg: MachineConfig) -> tuple[np.ndarray, np.ndarray]:
    """Each sample's point on the exact polyline of the block and chord ends, at the path length
    the samples moved (um), and that length."""
    a = run_arrays(ops, cfg)
    V = polyline(ops)
    seg = np.diff(V, axis=0)
    L = np.hypot(*seg.T)
    keep = L > 0
    V, seg, L = np.vstack([V[:1], V[1:][keep]]), seg[keep], L[keep]
    cum = np.concatenate([[0.0], np.cumsum(L)])
    s = np.cumsum(a.moved[a.kind == 0] / 65536.0)
    j = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(L) - 1)
    return V[j] + seg[j] * ((s - cum[j]) / L[j])[:, None], s


def arc_axis_accel(rng, n: int) -> dict[bool, list[float]]:
    """{arc_blocks: the largest sampled per-axis acceleration / the axis' limit inside each arc}."""
    out: dict[bool, list[float]] = {False: [], True: []}
    for _ in range(n):
        acc = (int(rng.integers(300, 5000)) * 1000, int(rng.integers(300, 5000)) * 1000)
        cfg = MachineConfig(origin_um=(0, 0), accel_um_s2=acc, max_feed_um_min=15_000_000)
        r, sweep = float(rng.uniform(2000, 20000)), float(rng.uniform(90, 360))
        pieces = [("line", 5000.0, 0.0), ("arc", r, sweep, float(rng.uniform(10, 200))), ("line", 5000.0, 0.0)]
        for ab in (False, True):
            c = dataclasses.replace(cfg, arc_blocks=ab)
            ops = arc_block_ops(pieces, c.max_feed_um_min, c) if ab else path_ops(pieces, c.max_feed_um_min)
            P, s = exact_points(ops, c)
            mid = s[1:-1]
            inside = (mid > 5300) & (mid < 5000 + r * np.radians(sweep) - 300)
            lim = np.asarray(acc, float) / cfg.sample_hz ** 2
            if inside.any():
                out[ab].append(float((np.abs(np.diff(P, 2, axis=0)[inside]) / lim).max()))
    return out


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
        arcs = dataclasses.replace(cfg, arc_blocks=True)
        a, b = path_ops(pieces, feed), arc_block_ops(pieces, feed, arcs)
        (ti0, tf0), (ti1, tf1) = job_seconds(a, cfg), job_seconds(b, arcs)
        ri.append(ti0 / ti1)
        rf.append(tf0 / tf1)
    print(f"random CAM paths ({args.paths}, 0.01-0.2 mm chords, lookahead 8): integer median {np.median(ri):.3f} "
          f"(min {min(ri):.3f}, max {max(ri):.3f}), float median {np.median(rf):.3f}")
    acc = arc_axis_accel(rng, args.paths)
    for ab, name in ((False, "chord blocks"), (True, "arc blocks")):
        print(f"sampled acceleration inside arcs / the axis limit, {name}: median {np.median(acc[ab]):.2f}, "
              f"max {max(acc[ab]):.2f} ({len(acc[ab])} arcs)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
