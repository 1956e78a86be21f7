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


def push_cycles(ops: list[tuple], cfg: MachineConfig, workdir: Path, src: Path = SRC) -> np.ndarray:
    """Cycles of each push on simavr (the ATmega328P at 16 MHz, -Os), with the planner's C from src."""
    workdir.mkdir(parents=True, exist_ok=True)
    (workdir / "nnik_gcode_config.h").write_text(header(cfg))
    wrap = workdir / "plpush.c"
    wrap.write_text(WRAP)
    rows, push = vectors(ops)
    r = run_avr([wrap, src / "nnik_plan.c", src / "nnik_plan_sample.c", src / "nnik_imath.c"], [workdir, src], "plpush", rows, workdir=workdir,
                n_out=2, progress=False, batch_size=4000)
    return r["cycles"][push]


def paths(cfg: MachineConfig) -> dict[str, list[tuple]]:
    feed = 1_800_000
    return {"0.1 mm chords": chord_ops(100.0, 5000.0, 1.0, feed),
            "0.5 mm chords": chord_ops(500.0, 20000.0, 1.0, feed),
            "3 mm lines, 30 deg": path_ops([("line", 3000.0, 30.0)] * 60, feed),
            "corners and reversals": path_ops([("line", 2000.0, 90.0), ("rev", 1000.0), ("line", 500.0, 45.0)] * 20,
                                              feed)}


def job_paths(scenario: str, jobs: list[str], plan_blocks: int) -> tuple[MachineConfig, dict[str, list[tuple]]]:
    """The shipped jobs' planner operations on a shipped scenario's machine (as `nnik job` sends them)."""
    from dataclasses import replace

    from nnik.firmware.config import default_machine
    from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
    from nnik.firmware.gcode.motion import interpret
    from nnik.firmware.gcode.reader import sendable
    from nnik.machine.scenario import load_scenario

    root = Path(__file__).resolve().parents[2] / "datasets"
    cfg = replace(default_machine(load_scenario(root / f"{scenario}.toml")), plan_blocks=plan_blocks, bounds_um=None)
    out = {}
    for job in jobs:
        path = root / "jobs" / f"{job}.gcode"
        lines = [sendable(ln).decode("latin-1") for ln in prepare(read_job(path), cfg, JobOptions(), str(path)).lines]
        out[job] = interpret(lines, cfg).ops
    return cfg, out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plan-blocks", type=int, default=8)
    ap.add_argument("--scenario", help="a shipped scenario whose machine runs --jobs (default: synthetic paths)")
    ap.add_argument("--jobs", default="circle,star,l_path", help="shipped jobs (datasets/jobs), comma-separated")
    ap.add_argument("--src", type=Path, default=SRC, help="the planner's C sources (another checkout's, to compare)")
    a = ap.parse_args(argv)
    if a.scenario:
        cfg, todo = job_paths(a.scenario, a.jobs.split(","), a.plan_blocks)
    else:
        cfg = MachineConfig(origin_um=(0, 0), plan_blocks=a.plan_blocks)
        todo = paths(cfg)
    with tempfile.TemporaryDirectory(prefix="nnik-plpush-") as d:
        for k, (name, ops) in enumerate(todo.items()):
            c = push_cycles(ops, cfg, Path(d) / str(k), a.src)
            print(f"{name:24s} pushes {len(c):5d}  cycles a push: mean {c.mean():8.0f}  max {c.max():7d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
