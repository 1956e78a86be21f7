"""`make bench`, the search part: the issue-9 goals, measured.

For a scenario (galvo_cba2012 by default) a fresh N-trial `nnik search` runs (its study is
started over), then the ladder of `nnik run` is fitted on the same problem. The table shows the
search's wall time and trials per minute, the families on its Pareto front, how many of the
front's points that meet max_error ran on the simulators (and how long that took), its verified
pick, and the pick against the ladder's: both by estimated cycles on the [target] chip (the
ladder's cheapest configuration that meets max_error), and the search pick's measured cycles.
Figures go to build/bench/search_<scenario>.json too.

Goals: N = 200 trials in <= 15 minutes on every shipped scenario (the default: all of them); the
pick at least as cheap as the ladder's; on galvo_cba2012 the front spans at least three families.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from nnik import pipeline
from nnik import selection as sel
from nnik.errors import NnikError
from nnik.machine.scenario import load_scenario
from nnik.search.storage import JOURNAL_FILE

console = Console(highlight=False, width=None if sys.stdout.isatty() else 160)
DATASETS = Path(__file__).resolve().parents[2] / "datasets"
OUT = Path("build") / "bench"
GOAL_MINUTES = 15.0
GOAL_FAMILIES = 3
GOAL_FAMILIES_ON = "galvo_cba2012"


def shipped() -> list[str]:
    """Every shipped scenario with an IK to search (datasets/*.toml; a dc_servo xy_table's closed
    loop has none: nnik.bench.servo measures it)."""
    return sorted(p.stem for p in DATASETS.glob("*.toml") if load_scenario(p).servo is None)


def trained_dir(name: str) -> Path:
    scn = load_scenario(DATASETS / f"{name}.toml")
    out = OUT / f"search_{name}"
    try:
        if pipeline.load_pair(out)[0].scenario.fingerprint == scn.fingerprint and (out / pipeline.METRICS_FILE).is_file():
            return out
    except NnikError:
        pass
    pipeline.generate(scn, out)
    pipeline.train(scn, out, progress=False)
    pipeline.evaluate(out)
    return out


def ladder_pick(out: Path) -> sel.Candidate | None:
    """The ladder's cheapest configuration that meets max_error, by estimated cycles on the chip."""
    problem = pipeline.problem_for(out)
    target = problem.scn.target
    cands = sel.fit_ladder(problem, max_error=target["max_error"])
    ok = [c for c in cands if c.meets(target["max_error"])]
    chip = target["chip"]
    return min(ok, key=lambda c: (c.est[chip]["cycles"], c.est[chip]["flash_bytes"])) if ok else None


def bench(name: str, trials: int, jobs: int) -> dict:
    out = trained_dir(name)
    (out / JOURNAL_FILE).unlink(missing_ok=True)
    from nnik.cli import main as nnik_main  # the command as a user runs it (only the CLI imports nnik.search.study)

    t0 = time.perf_counter()
    rc = nnik_main(["search", str(out), "--trials", str(trials), "--jobs", str(jobs)])
    minutes = (time.perf_counter() - t0) / 60
    res = pipeline.load_metrics(out)
    err = None if rc == 0 else f"nnik search exited {rc}"
    s, selection = res["search"], res["selection"]
    chip = selection["target"]["chip"]
    pick = next((r for r in selection["implementations"] if r.get("picked")), None)
    lad = ladder_pick(out)
    row = {"scenario": name, "trials": trials, "jobs": jobs, "minutes_total": minutes,
           "search_minutes": s["seconds"] / 60, "trials_per_min": s["trials_per_min"],
           "front_points": len(s["front"]), "front_families": s["front_families"], "error": err,
           "front_verified": s.get("front_verified"),
           "pick": None if pick is None else {"describe": pick["describe"], "pre_max": pick["pre_max"],
                                              "est_cycles": pick["estimate"][chip]["cycles"],
                                              "cycles": pick["cycles"][chip], "flash_bytes": pick["flash_bytes"][chip]},
           "ladder_pick": None if lad is None else {"describe": lad.impl.describe(), "pre_max": lad.acc["pre_max"],
                                                    "est_cycles": lad.est[chip]["cycles"]}}
    row["goals"] = {"minutes": minutes <= GOAL_MINUTES,
                    "cheaper_or_equal": bool(pick and (lad is None or pick["estimate"][chip]["cycles"]
                                                       <= lad.est[chip]["cycles"] + 1e-9)),
                    **({"families": len(s["front_families"]) >= GOAL_FAMILIES} if name == GOAL_FAMILIES_ON else {})}
    return row


def _verified_cell(v: dict) -> str:
    """How many front points that meet max_error ran on the simulators, of how many, in how long."""
    if "cap" not in v:
        return "-"
    return f"{v['verified']} of {v['meeting_max_error']} (cap {v['cap']}) in {v['seconds']:.0f} s"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.search")
    ap.add_argument("scenarios", nargs="*", help="shipped scenario names (default: all of them)")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args(argv)
    rows = [bench(n, a.trials, a.jobs) for n in a.scenarios or shipped()]
    t = Table(title=f"nnik search: {a.trials} trials, {a.jobs} job(s) (goals: <= {GOAL_MINUTES:g} min, pick <= ladder, "
                    f">= {GOAL_FAMILIES} families on the front of {GOAL_FAMILIES_ON})")
    for c in ("scenario", "minutes", "trials/min", "front families", "front verified",
              "search pick (est / measured cycles)", "ladder pick (est cycles)", "goals met"):
        t.add_column(c)
    for r in rows:
        p, lp = r["pick"], r["ladder_pick"]
        t.add_row(r["scenario"], f"{r['minutes_total']:.1f}", f"{r['trials_per_min'] or 0:.1f}",
                  f"{len(r['front_families'])}: {', '.join(r['front_families'])} ({r['front_points']} points)",
                  _verified_cell(r.get("front_verified") or {}),
                  "-" if p is None else f"{p['describe'][:50]}: {p['est_cycles']:.0f} / {p['cycles']:.0f}",
                  "-" if lp is None else f"{lp['describe'][:50]}: {lp['est_cycles']:.0f}",
                  ", ".join(f"{k} {'yes' if v else 'NO'}" for k, v in r["goals"].items()))
    console.print(t)
    OUT.mkdir(parents=True, exist_ok=True)
    for r in rows:
        (OUT / f"search_{r['scenario']}.json").write_text(json.dumps(r, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
