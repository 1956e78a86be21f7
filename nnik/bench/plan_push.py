"""The planner's cost per block on the ATmega328P (simavr): nnik_pl_push alone, timed per call,
with the sampler run between pushes (untimed) as nnik_gcode.c does (it samples while the queue is
full, then pushes). `python3 -m nnik.bench.plan_push` prints cycles per push on a few paths (CAM
chords, corners, a real job's moves)."""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from nnik.bench.planner_paths import chord_ops, path_ops
from nnik.firmware.config import MachineConfig
from nnik.targets.avr import run_avr
from nnik.targets.toolchain import HARNESS_DIR

SRC = HARNESS_DIR.parent / "arduino" / "src"
# one op per call: 0 init at (x, y); 1 push (x, y, feed) (the timed one); 2 sample while ready
WRAP = """#include "nnik_plan.h"
static nnik_plan_t pl;
int8_t plpush_ik(const int32_t in[4], int32_t out[2])
{
    nnik_pl_sample_t s;
    int32_t n = 0;
    if (in[0] == 0) {
        int32_t p[2] = {in[1], in[2]};
        nnik_pl_init(&pl, p);
    } else if (in[0] == 1) {
        nnik_pl_push(&pl, in[1], in[2], in[3], 0);
    } else {
        while (nnik_pl_ready(&pl, (uint8_t)in[1])) {
            nnik_pl_sample(&pl, &s);
            n++;
        }
    }
    out[0] = n;
    out[1] = pl.count;
    return 0;
}
"""


def vectors(ops: list[tuple]) -> tuple[np.ndarray, np.ndarray]:
    """The ops as harness rows, and which rows are pushes."""
    rows, push = [[0, 0, 0, 0]], [False]
    for op in ops:
        if op[0] == "push":
            rows.append([2, 0, 0, 0])
            push.append(False)
            rows.append([1, op[1], op[2], op[3]])
            push.append(True)
        else:
            rows.append([2, 1, 0, 0])
            push.append(False)
    rows.append([2, 1, 0, 0])
    push.append(False)
    return np.asarray(rows, dtype=np.int64), np.asarray(push)


def header(cfg: MachineConfig) -> str:
    lines = ["#ifndef NNIK_GCODE_CONFIG_H", "#define NNIK_GCODE_CONFIG_H"]
    lines += [f"#define {k} {v}" for k, v in cfg.motion_defines().items() if not k.startswith("NNIK_SH")]
    return "\n".join(lines + ["#endif", ""])


def push_cycles(ops: list[tuple], cfg: MachineConfig, workdir: Path) -> np.ndarray:
    """Cycles of each push on simavr (the ATmega328P at 16 MHz, -Os)."""
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / "nnik_gcode_config.h").write_text(header(cfg))
    wrap = workdir / "plpush.c"
    wrap.write_text(WRAP)
    rows, push = vectors(ops)
    r = run_avr([wrap, SRC / "nnik_plan.c", SRC / "nnik_imath.c"], [workdir, SRC], "plpush", rows, workdir=workdir,
                n_out=2, progress=False, batch_size=4000)
    return r["cycles"][push]


def paths(cfg: MachineConfig) -> dict[str, list[tuple]]:
    feed = 1_800_000
    return {"0.1 mm chords": chord_ops(100.0, 5000.0, 1.0, feed),
            "0.5 mm chords": chord_ops(500.0, 20000.0, 1.0, feed),
            "3 mm lines, 30 deg": path_ops([("line", 3000.0, 30.0)] * 60, feed),
            "corners and reversals": path_ops([("line", 2000.0, 90.0), ("rev", 1000.0), ("line", 500.0, 45.0)] * 20,
                                              feed)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plan-blocks", type=int, default=8)
    a = ap.parse_args(argv)
    cfg = MachineConfig(origin_um=(0, 0), plan_blocks=a.plan_blocks)
    with tempfile.TemporaryDirectory(prefix="nnik-plpush-") as d:
        for k, (name, ops) in enumerate(paths(cfg).items()):
            c = push_cycles(ops, cfg, Path(d) / str(k))
            print(f"{name:24s} pushes {len(c):5d}  cycles a push: mean {c.mean():8.0f}  max {c.max():7d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
