"""Cycles per arc chord on simavr (ATmega328P, -Os) of the parts an arc-block chip would
run, against today's push: gen = nnik_gc_chords_next alone; gen+line = the chord pushed into an
empty queue (its length, u, vn, acc: what the sampler would recompute per chord, an upper bound);
gen+junction = pushed behind one block (+ the junction and a 2-block backward pass); today =
plan_push's measurement (a queue of 12) on the same chords.  What the figures decide: an arc
block whose sampler regenerates the chords (bisection, length, u) and whose push checks every
vertex's junction costs more per chord than today's push; it pays only with chords that are
cheaper to walk (see docs/motion.md, "Arcs as one block").

    python3 -m nnik.bench.arc_chord_cost [R_UM SEG_UM]...   (default: 8000 500 and 3000 100)
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from nnik.bench.plan_push import SRC, header, push_cycles
from nnik.firmware.config import MachineConfig
from nnik.firmware.gcode.geometry import arc_points
from nnik.targets.avr import run_avr

WRAP = r'''
#include "nnik_plan.h"
#include "nnik_gc_geom.h"
static nnik_plan_t pl;
static nnik_gc_chords_t it;
int8_t arcc_ik(const int32_t in[4], int32_t out[2])
{
    int32_t q[2];
    out[0] = out[1] = 0;
    if (in[0] == 0) {
        int32_t p[2] = {in[1], in[2]};
        nnik_gc_arc_start(&it, in[1], in[2], in[1], in[2], (uint32_t)in[3], 1);
        nnik_pl_init(&pl, p);
        return 0;
    }
    out[0] = nnik_gc_chords_next(&it, q);
    if (in[0] == 2 || in[0] == 3) {
        nnik_pl_push(&pl, q[0], q[1], 1500000L, 0);
        if (in[0] == 2 || pl.count > 1) { /* keep in[0] - 2 blocks queued: drop the head */
            pl.head = (uint8_t)((pl.head + 1) % NNIK_PL_N);
            pl.count--;
        }
    }
    out[1] = q[0];
    return 0;
}
'''

def chord_costs(r: int, seg: int) -> dict[str, np.ndarray]:
    """Cycles per chord of a full circle of radius r um in chords of at most seg um, by part."""
    cfg = MachineConfig(origin_um=(0, 0), seg_um=seg, plan_blocks=12)
    n = len(arc_points((r, 0), (r, 0), r, True, seg))
    res = {}
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        (d / "nnik_gcode_config.h").write_text(header(cfg).replace("#endif", f"#define NNIK_GC_SEG_UM {seg}\n#define NNIK_GC_G5 0\n#endif"))
        (d / "arcc.c").write_text(WRAP)
        for mode, name in ((1, "gen"), (2, "gen+line"), (3, "gen+junction")):
            rows = [[0, r, 0, r]] + [[mode, 0, 0, 0]] * n
            out = run_avr([d / "arcc.c", SRC / "nnik_plan.c", SRC / "nnik_imath.c", SRC / "nnik_gc_geom.c"], [d, SRC], "arcc",
                          np.asarray(rows), workdir=d / str(mode), n_out=2, progress=False)
            res[name] = out["cycles"][1:]
        pts = arc_points((r, 0), (r, 0), r, True, seg)  # offsets from the centre (0, 0): the same chords
        ops = [("push", r, 0, 1500000, 0, 0)] + [("push", x, y, 1500000, 0, i + 1) for i, (x, y) in enumerate(pts)]
        res["today: push (queue of 12)"] = push_cycles(ops + [("flush",)], cfg, d / "today")[1:]
    return res


def main(argv=None) -> int:
    args = [int(a) for a in (sys.argv[1:] if argv is None else argv)] or [8000, 500, 3000, 100]
    for r, seg in zip(args[::2], args[1::2]):
        res = chord_costs(r, seg)
        print(f"circle of radius {r} um, {len(res['gen'])} chords of at most {seg} um: AVR cycles a chord")
        for k, c in res.items():
            print(f"  {k:28s} mean {c.mean():7.0f}  max {c.max():7d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
