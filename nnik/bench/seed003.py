"""`make bench`, seed 003's table reproduced: its L path (10 mm in X, then 10 mm in Y, from rest)
on its base-excited belt model, the reference case and its ten variations (Table 4.3).

For each case, the tip's max and RMS distance to the programmed path (um) and the job's time:
  * none: the firmware's planner (trapezoids, junction deviation) and no compensation;
  * zv / mzv / zvd / ei: the firmware's fixed-point shaper at the case's (f, zeta);
  * least squares: the seed's own setting and problem (what its fmincon solved): a base on the
    grid of the case's time step, linearly interpolated, fitted so the modelled tip follows the
    planned motion; the tip is linear in the grid values, so one linear solve does it
    (nnik.dynamics.precompensate.least_squares); no firmware, no microsteps;
  * precompensated job: `nnik job --precompensate`, model inversion on a snap-limited reference
    written as G-code and run through the firmware's planner, which re-plans it (what a user
    flashing it gets).
The firmware's runs are its Python model (bit for bit the simulated chip's steps, tests/firmware/
gcode), on corexy_nonlinear's pick, at the case's acceleration and speed; the tip follows each
Cartesian axis's spring-damper (nnik.dynamics.axis) from the steps.  The firmware samples at
1 kHz (2 kHz where the speed needs it); the seed's time step applies to the least squares only.
Results: build/bench/seed003.json and the table printed.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from nnik.dynamics.axis import tip_xy
from nnik.dynamics.precompensate import least_squares
from nnik.firmware.config import default_machine
from nnik.firmware.gcode.compensation import METHODS, compare
from nnik.firmware.gcode.contour import path_dist_um

console = Console(highlight=False, width=None if sys.stdout.isatty() else 200)
DATASETS = Path(__file__).resolve().parents[2] / "datasets"
OUT = Path("build") / "bench"
REFERENCE = {"w": 100.0, "zeta": 0.5, "a": 5000.0, "v": 100.0, "dt": 0.005}
VARIATIONS = [("w", 50.0), ("w", 200.0), ("zeta", 0.0), ("zeta", 1.0), ("a", 1000.0), ("a", 10000.0),
              ("v", 50.0), ("v", 200.0), ("dt", 0.1), ("dt", 0.001)]
TICK_FINE = 10  # the least squares' base is simulated at 10 points per millisecond


def cases() -> list[tuple[str, dict]]:
    out = [("reference", dict(REFERENCE))]
    for key, val in VARIATIONS:
        c = dict(REFERENCE)
        c[key] = val
        out.append((f"{key} = {val:g}", c))
    return out


def l_path(v: float) -> list[str]:
    return ["G21 G90", f"G1 X10 Y0 F{v * 60:g}", "G1 X10 Y10", "M400"]


def machine(scn, case: dict):
    """corexy_nonlinear's firmware settings at the case's acceleration and speed."""
    base = default_machine(scn)
    fs = 1000 if case["v"] * 60 <= 7000 else 2000
    return replace(base, accel_um_s2=(int(case["a"] * 1000),) * 2, max_feed_um_min=int(case["v"] * 60_000),
                   sample_hz=fs, shaper="none", shaper_taps=())


def seed_setting(run_none, cfg, dyn: dict, dt: float) -> dict:
    """The seed's setting: a base on a grid of the case's time step, linearly interpolated in
    between, fitted so the modelled tip follows the planned motion (nnik.dynamics.precompensate.
    least_squares: one linear solve, where the seed iterated fmincon); no firmware, no
    microsteps.  The tip is simulated every 0.1 ms with 0.3 s of rest after the end."""
    _, plan, seg, _ = run_none
    planned = np.concatenate([np.zeros((1, 2)), seg.planned_um[seg.kind == 0] / 1000.0])
    planned = np.concatenate([planned, np.repeat(planned[-1:], int(0.3 * cfg.sample_hz), 0)])
    t_fw = np.arange(len(planned)) / cfg.sample_hz
    fine_dt = dt / 5
    ts = np.arange(0.0, t_fw[-1], fine_dt)
    target = np.stack([np.interp(ts, t_fw, planned[:, i]) for i in range(2)], 1)
    t0 = time.perf_counter()
    base = least_squares(target, fine_dt, dt, dyn["f_hz"], dyn["zeta"])
    secs = time.perf_counter() - t0
    grid = np.arange(len(base)) * dt
    t_sim = np.arange(0.0, t_fw[-1], 1e-3 / TICK_FINE)
    fine = np.stack([np.interp(t_sim, grid, base[:, i]) for i in range(2)], 1)
    tip = tip_xy(fine, 1e-3 / TICK_FINE, dyn["f_hz"], dyn["zeta"])
    origin = np.asarray(cfg.origin_um, float) / 1000.0
    zero = np.zeros(len(tip), np.int64)
    # the L's two moves: the distance to the nearer (the path does not cross itself)
    d = np.minimum(path_dist_um(tip + origin, zero, plan.moves[:1], origin),
                   path_dist_um(tip + origin, zero, plan.moves[1:2], origin))
    return {"contour_um": {"max": float(d.max()), "rms": float(np.sqrt((d**2).mean()))},
            "seconds": float(seg.ticks.sum() / cfg.tick_hz), "compute_s": secs}


def run_case(outdir: Path, scn, ik, case: dict) -> dict:
    cfg = machine(scn, case)
    f = case["w"] / (2 * math.pi)
    dyn = {"f_hz": (f, f), "zeta": (case["zeta"], case["zeta"])}
    res = compare(scn, cfg, l_path(case["v"]), ik, dyn, "seed 003 L path", methods=METHODS, robust=False)
    out = {"sample_hz": cfg.sample_hz}
    for m, r in res.items():
        r.pop("run", None)
        r.pop("gcode", None)
        out[m] = r
    if "none" in res and "error" not in res["none"]:
        from nnik.firmware.gcode.compensation import model_run

        out["least squares"] = seed_setting((cfg,) + model_run(l_path(case["v"]), cfg, ik), cfg, dyn, case["dt"])
    return out


def _cell(r: dict | None) -> str:
    if not r:
        return "-"
    if "error" in r:
        return "n/a"
    return f"{r['contour_um']['max']:.1f} / {r['contour_um']['rms']:.1f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.seed003", description=__doc__.split("\n\n")[0])
    ap.add_argument("--outdir", default=str(OUT / "seed003_corexy"), help="corexy_nonlinear's run (made if missing)")
    args = ap.parse_args(argv)
    from nnik import pipeline
    from nnik.files.pick_state import status
    from nnik.firmware.ik_oracle import ik_oracle, load_scenario_of
    from nnik.machine.scenario import load_scenario

    outdir = Path(args.outdir)
    if status(outdir).state == "none":
        console.print(f"training corexy_nonlinear into {outdir} (nnik run) ...")
        pipeline.run(load_scenario(DATASETS / "corexy_nonlinear.toml"), outdir)
    scn = load_scenario_of(outdir)
    ik = ik_oracle(outdir)
    rows, figures = [], {}
    t0 = time.perf_counter()
    for name, case in cases():
        r = run_case(outdir, scn, ik, case)
        figures[name] = {"case": case, **r}
        rows.append((name, r))
    cols = ["none", "zv", "mzv", "zvd", "ei", "precompensated", "least squares"]
    t = Table(title="Seed 003's L path: the tip's max / RMS distance to the path (um); job time; "
                    "the least squares' compute time")
    for h in ["case", "fs"] + cols[:-1] + ["least squares", "time none / best", "its compute"]:
        t.add_column(h)
    for name, r in rows:
        ok = {m: r[m] for m in cols if m in r and "error" not in r[m]}
        if "none" not in ok:
            t.add_row(name, f"{r['sample_hz']}", *["n/a"] * len(cols), r["none"]["error"], "")
            continue
        best = min(ok, key=lambda m: ok[m]["contour_um"]["max"])
        t.add_row(name, f"{r['sample_hz']}", *[_cell(r.get(m)) for m in cols],
                  f"{r['none']['seconds']:.3f} / {ok[best]['seconds']:.3f} ({best})",
                  f"{r['least squares']['compute_s']:.2f} s")
    console.print(t)
    ref = figures["reference"]
    ratio = ref["least squares"]["contour_um"]["max"] / ref["none"]["contour_um"]["max"]
    console.print(f"reference case: least squares {ref['least squares']['contour_um']['max']:.1f} um against "
                  f"{ref['none']['contour_um']['max']:.1f} um uncompensated ({100 * ratio:.1f} %), computed in "
                  f"{ref['least squares']['compute_s']:.2f} s (the seed's fmincon: up to 93 s); "
                  f"whole bench {time.perf_counter() - t0:.1f} s")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "seed003.json").write_text(json.dumps(figures, indent=2, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
