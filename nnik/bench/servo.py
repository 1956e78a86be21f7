"""`python -m nnik.bench.servo [SCENARIO]`: the closed-loop controller on the simulated Uno (issue 28
item 8), default datasets/xy_table.toml:

- per controller: `controller cycles per tick: max N` (the busy pin's cycles: the controller and
  the outputs' writes, both axes, nested encoder interrupts out; the PID's budget is 800 per axis,
  nn_vector's 7,000 and nn_axes' 12,000 for the forward, backward and update: BUDGETS), on the
  seed's steps (25 mm X, 20 mm Y, there and back at full duty: the motors' top speed);
- the tick's total load on that job, every encoder interrupt included, as CPU % (the cycles the chip
  is awake in the busiest tick: its main loop sleeps; the budget 50 % of the tick), at the
  scenario's tick (5 ms) and, for the fixed-gain controllers, at 1 ms (a neural controller's tick
  does not fit 1 ms);
- mismatch N: the ticks where the chip's duty, or a neural controller's weights' checksum, differs
  from the integer model's;
- the highest encoder edge rate two axes sustain (nnik.firmware.servo.edge_rate), in edges/s per
  axis and mm/s at the scenario's um per count;
- flash and RAM of each build (avr-size: .text + .data, .data + .bss);
- the co-simulation's speed, ticks per second of wall time (the only timed figure; it decides
  nothing).

Gains: GAINS below, a hand-set start for each fixed-gain controller (the cycles follow the code's
paths, with the duty saturated or not, more than the gains' values); the neural controllers
pretrained here as `nnik run` does (the scenario's plant identified, nnik.job.servo_pretrain on the
identified models, the [controller] seed: about 20 s), so they learn on the steps as shipped.
`--gains MODEL_DIR` takes a run's tuned gains and pretrained params from MODEL_DIR/servo/gains.json.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
GAINS = {
    "pid": dict(kp_x=2.0, ki_x=4.0, kd_x=0.02, kp_y=1.5, ki_y=3.0, kd_y=0.03),
    "pdff": dict(kp_x=2.0, kd_x=0.02, kv_x=0.02, ka_x=2e-4, kp_y=1.5, kd_y=0.03, kv_y=0.03, ka_y=3e-4),
    "ccc": dict(kp_x=2.0, ki_x=4.0, kd_x=0.02, kp_y=1.5, ki_y=3.0, kd_y=0.03, kcp=3.0, kcd=0.02),
}
BUDGETS = {"pid": 1600, "nn_vector": 7000, "nn_axes": 12000}  # controller cycles per tick, both axes (issues 28, 29)
CPU_BUDGET_PCT = 50.0  # the tick's whole load with the encoder interrupts at top speed (issue 29)


def load_gains(scn, gains_dir: Path | None = None, say=None) -> dict:
    """kind -> gains (GAINS) or params for every controller: a run's (gains_dir/servo/gains.json)
    where it has them; the neural ones it lacks pretrained here."""
    from nnik.implementations.servo import NEURAL

    gains = dict(GAINS)
    run_file = None if gains_dir is None else Path(gains_dir) / "servo" / "gains.json"
    if run_file is not None and run_file.is_file():
        gains.update(json.loads(run_file.read_text())["gains"])
    missing = [k for k in NEURAL if k not in gains]
    if missing:
        from nnik.commands.servo_run import identify
        from nnik.job.servo_pretrain import pretrain_all

        fits = identify(scn, scn.controller["seed"])
        params, _ = pretrain_all(scn, tuple(f.model for f in fits), tuple(f.coulomb_v for f in fits),
                                 scn.controller["seed"], say=say or (lambda line: None), kinds=tuple(missing))
        gains.update(params)
    return gains


def steps_job(cfg, seconds_each: float = 1.5) -> np.ndarray:
    """The seed's steps, 25 mm on X and 20 mm on Y at once, held, then back to 0: (N, 2) counts."""
    n = max(2, round(seconds_each / cfg.tick_s))
    target = np.array([round(25000 / cfg.um_per_count), round(20000 / cfg.um_per_count)], dtype=np.int64)
    return np.concatenate([np.tile(target, (n, 1)), np.zeros((n, 2), np.int64)])


def at_tick(cfg, tick_s: float):
    """cfg at another tick, with the plant's substep length kept (at least 4 substeps)."""
    return replace(cfg, tick_s=tick_s, substeps=max(4, round(cfg.substeps * tick_s / cfg.tick_s)))


def measure_kind(kind: str, gains: dict, cfg, work: Path, seconds_each: float = 1.5) -> dict:
    """One controller at one tick: cycles, load, lost counts, mismatches, sizes, co-sim speed."""
    from nnik.firmware.servo.build import build_firmware
    from nnik.firmware.servo.cosim import run
    from nnik.implementations.servo import make

    ctl = make(kind, gains, cfg)
    fw = build_firmware(ctl, cfg.tick_s, work / f"{kind}-{cfg.tick_s:g}")
    ref = steps_job(cfg, seconds_each)
    t = time.perf_counter()
    tr = run(fw, cfg, ctl, ref, work / f"{kind}-{cfg.tick_s:g}" / "run")
    wall = time.perf_counter() - t
    edges = np.abs(np.diff(tr.plant_counts, axis=0)).max(axis=0) / cfg.tick_s
    return {"kind": kind, "tick_ms": cfg.tick_s * 1e3, "cycles_max": tr.cycles_max,
            "tick_isr_max": int(tr.tick_isr_cycles.max()), "enc_isr_max": int(tr.enc_cycles.max()),
            "load_pct": tr.load_pct_max, "mismatches": tr.mismatches, "lost": tr.lost_counts,
            "checksum_mismatches": int((tr.chip_sum != tr.model_sum).sum()),
            "top_edges_s": edges.tolist(), "flash": fw.flash_bytes, "ram": fw.ram_bytes,
            "ticks": len(ref), "ticks_per_s": len(ref) / wall if wall > 0 else float("inf"), "fw": fw}


def _budget(kind: str, r: dict) -> tuple[str, str]:
    b = BUDGETS.get(kind)
    cyc = "" if b is None else (f" (budget {b:,}: " + ("within" if r["cycles_max"] <= b else "OVER") + ")")
    return cyc, "within" if r["load_pct"] <= CPU_BUDGET_PCT else "OVER"


def report(scenario: Path, gains_dir: Path | None = None, seconds_each: float = 1.5, edge_ticks: int = 20,
           out=sys.stdout, gains: dict | None = None) -> list[dict]:
    """gains: kind -> gains or params of the controllers to measure (default: every kind, load_gains)."""
    from nnik.firmware.servo.edge_rate import max_edge_rate
    from nnik.implementations.servo import NEURAL
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(scenario)
    cfg = scn.servo
    if cfg is None:
        raise SystemExit(f"nnik: error: {scenario} has no [servo] table")
    gains = gains if gains is not None else load_gains(scn, gains_dir)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for kind in gains:
            ticks = [cfg.tick_s] if kind in NEURAL else sorted({cfg.tick_s, 0.001}, reverse=True)
            for tick_s in ticks:
                r = measure_kind(kind, gains[kind], at_tick(cfg, tick_s), work, seconds_each)
                rows.append(r)
                cyc, cpu = _budget(kind, r)
                print(f"{kind:<9} tick {r['tick_ms']:g} ms: controller cycles per tick: max {r['cycles_max']}{cyc}; "
                      f"tick ISR max {r['tick_isr_max']}; CPU {r['load_pct']:.1f} % ({cpu} {CPU_BUDGET_PCT:g} %) with "
                      f"the encoder ISRs at top speed ({max(r['top_edges_s']):,.0f} edges/s, {r['enc_isr_max']} "
                      f"encoder ISR cycles in a tick); mismatch {r['mismatches']} (checksum "
                      f"{r['checksum_mismatches']}), lost {r['lost']}; flash {r['flash']:,} B, RAM {r['ram']} B; "
                      f"co-sim {r['ticks_per_s']:,.0f} ticks/s", file=out)
        e = max_edge_rate(rows[0]["fw"], work / "edges", ticks=edge_ticks)
        print(f"max encoder edge rate, both axes at once ({rows[0]['kind']}, {rows[0]['tick_ms']:g} ms tick): "
              f"{e.rate:,.0f} edges/s per axis = {e.rate * cfg.um_per_count / 1000:.1f} mm/s at "
              f"{cfg.um_per_count:g} um/count (CPU {e.awake_max / e.period * 100:.1f} %, no count lost)", file=out)
        rows.append({"kind": "edges", "rate": e.rate, "mm_s": e.rate * cfg.um_per_count / 1000})
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m nnik.bench.servo")
    p.add_argument("scenario", nargs="?", default=str(ROOT / "datasets" / "xy_table.toml"))
    p.add_argument("--gains", type=Path, default=None, help="a `nnik run` output dir (its servo/gains.json)")
    a = p.parse_args(argv)
    report(Path(a.scenario), a.gains)
    return 0


if __name__ == "__main__":
    sys.exit(main())
