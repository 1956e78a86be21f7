"""`make bench`, the families part: the issue-8 goals, measured on the simulators.

For each goal (scenario, chip, max_error), nnik's selection runs as in ``nnik run`` (every
family's ladder, each family's best verified bit-exact on host, simavr and gpsim, the pick by
measured cycles) and the table shows the pick, its measured cycles and flash on both chips, each
family's best point, and whether the goal is met. Figures go to build/bench/families.json too.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

from rich.console import Console
from rich.table import Table

from nnik import pipeline
from nnik.errors import NnikError
from nnik.machine.scenario import load_scenario

console = Console(highlight=False, width=None if sys.stdout.isatty() else 160)
DATASETS = Path(__file__).resolve().parents[2] / "datasets"
OUT = Path("build") / "bench"


@dataclass(frozen=True)
class Goal:
    scenario: str
    max_error: float
    chip: str = "avr"
    max_cycles: float | None = None  # on the chip
    max_flash: int | None = None  # model flash on the chip
    pic18_cycles: float | None = None  # the same pick on pic18


GOALS = (
    Goal("galvo_cba2012", 0.01, max_cycles=500, max_flash=800, pic18_cycles=1200),
    Goal("galvo_cba2012", 0.1, max_cycles=420, pic18_cycles=1200),
    Goal("galvo_dual_xy2", 1.0, max_cycles=550, max_flash=1024, pic18_cycles=1200),
    Goal("corexy_nonlinear", 0.25, max_cycles=1200),
    Goal("hbot_unicamp", 0.25),
    Goal("corexy_measured", 1.0),
)


def ensure_trained(name: str) -> Path:
    scn = load_scenario(DATASETS / f"{name}.toml")
    out = OUT / name
    if not (out / pipeline.MODEL_FILE).is_file() or not (out / pipeline.METRICS_FILE).is_file():
        pipeline.generate(scn, out)
        pipeline.train(scn, out)
        pipeline.evaluate(out)
    return out


def run_goal(g: Goal) -> dict:
    out = ensure_trained(g.scenario)
    try:
        target = {"chip": g.chip, "max_error": g.max_error}
        if g.max_flash:  # a user asking for both states both: the flash limit is part of the target
            target["max_flash_bytes"] = g.max_flash
        sec = pipeline.select(out, target=target)
        error = None
    except NnikError as exc:
        sec, error = pipeline.load_metrics(out)["selection"], str(exc)
    pick = next((r for r in sec["implementations"] if r["picked"]), None)
    res = {"goal": g.__dict__, "error": error, "implementations": sec["implementations"], "pick": pick,
           "unit": pipeline.load_metrics(out)["unit"]}
    checks = []
    if pick:
        cyc, fl = pick["cycles"], pick["flash_bytes"]
        if g.max_cycles:
            checks.append(cyc[g.chip] <= g.max_cycles)
        if g.max_flash:
            checks.append(fl[g.chip] <= g.max_flash)
        if g.pic18_cycles:
            checks.append(cyc["pic18"] <= g.pic18_cycles)
    res["met"] = bool(pick) and all(checks)
    return res


def goal_text(g: dict) -> str:
    parts = [f"<= {g['max_cycles']:.0f} cyc" if g["max_cycles"] else "",
             f"<= {g['max_flash']} B" if g["max_flash"] else "",
             f"pic18 <= {g['pic18_cycles']:.0f}" if g["pic18_cycles"] else ""]
    return ", ".join(p for p in parts if p) or "a pick"


def table(results: list[dict]) -> Table:
    t = Table(title="issue 8 goals: the pick per scenario and max_error (measured: mean cycles per call on "
                    "simavr / gpsim, model flash bytes; error: pre-rounding max on the dense check grid)")
    for c in ("scenario", "max_error", "pick", "pre max", "avr cyc", "pic18 cyc", "avr B", "pic18 B",
              "best of each other family (pre max, avr cyc)", "goal", "met"):
        t.add_column(c, justify="right" if c in ("max_error", "pre max", "avr cyc", "pic18 cyc", "avr B", "pic18 B") else "left")
    for r in results:
        g, p = r["goal"], r["pick"]
        others = "; ".join(f"{o['family']} {o['pre_max']:.3g}, {o['cycles'].get('avr', float('nan')):.0f}"
                           if o.get("cycles") else f"{o['family']} {o['pre_max']:.3g}"
                           for o in r["implementations"] if not o["picked"])
        if p:
            t.add_row(g["scenario"], f"{g['max_error']:g} {r['unit']}", p["describe"], f"{p['pre_max']:.4f}",
                      f"{p['cycles']['avr']:.0f}", f"{p['cycles']['pic18']:.0f}", str(p["flash_bytes"]["avr"]),
                      str(p["flash_bytes"]["pic18"]), others, goal_text(g), "yes" if r["met"] else "NO")
        else:
            t.add_row(g["scenario"], f"{g['max_error']:g} {r['unit']}", f"none: {r['error']}", "", "", "", "", "",
                      others, goal_text(g), "NO")
    return t


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.families")
    ap.add_argument("--scenario", action="append", help="only these scenarios (default: every goal)")
    args = ap.parse_args(argv)
    goals = [g for g in GOALS if not args.scenario or g.scenario in args.scenario]
    results = []
    for g in goals:
        console.print(f"[bold]{g.scenario}[/bold]: max_error {g.max_error:g} on {g.chip} ...")
        results.append(run_goal(g))
    console.print(table(results))
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "families.json").write_text(json.dumps(results, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
