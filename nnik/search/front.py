"""The search's Pareto front, verified on the host and both simulated chips.

Every point of the front that meets max_error (cheapest on the [target] chip first, at most
MAX_VERIFY of them) runs on the host (gcc with UBSan and ASan) and on simavr and gpsim (the fast
path); its measured cycles and flash and the hash of the C it ran go into its front row. A point
that is a family's best keeps the full checks :func:`nnik.selection.verify_candidate` gave it
(portable paths too) and is not run again. The C of any other point is written to
OUTDIR/targets/front/<family>_<trial>/c/ (a family best's is c/alt/<family>/); the row's
``c_dir`` says which, so the report can tell when that C has changed since it was measured.
Points that miss max_error, or lie beyond the cap, keep their estimates and say why.
"""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

from nnik.implementations.base import TARGETS
from nnik.implementations.verify import verify_host, verify_on_target

MAX_VERIFY = 48  # front points that meet max_error verified on the simulators, cheapest first
FRONT_DIR = Path("targets") / "front"


def config_key(family: str, config: dict) -> str:
    return json.dumps([family, config], sort_keys=True)


def _checked(checks: dict) -> bool | None:
    """Every check that ran is bit-exact (None if none ran)."""
    ran = [c for c in checks.values() if isinstance(c, dict) and "not_run" not in c]
    return all(c.get("bit_exact") for c in ran) if ran else None


def verify_front(outdir: Path, rows: list[dict], cands: dict, bests: dict, target: dict, alt_dir: Path,
                 progress: bool = False) -> dict:
    """Verify the front rows in place (cheapest first, as they come); ``cands`` maps config_key to
    the refitted selection.Candidate, ``bests`` family -> Candidate (already verified where it meets
    max_error). Returns the summary that goes beside the front in metrics["search"]."""
    from nnik.progress import bar

    t0 = time.perf_counter()
    outdir = Path(outdir)
    shutil.rmtree(outdir / FRONT_DIR, ignore_errors=True)  # no C left from an earlier front
    max_err = target["max_error"]
    todo, verified = [], 0
    for r in rows:
        c = cands.get(config_key(r["family"], r["config"]))
        r["meets_max_error"] = bool(r.get("claimed_max", r["pre_max"]) <= max_err)
        if c is None or c.impl is None:
            r["not_verified"] = "not refitted" if c is None else f"could not be refitted: {c.skipped}"
            continue
        r["estimate"] = {t: {k: c.est[t][k] for k in ("cycles", "flash_bytes") if k in c.est[t]} for t in c.est}
        r["model_hash"] = c.impl.source_hash()
        if not c.meets(max_err):
            r["not_verified"] = f"misses max_error {max_err:g}: estimate only"
        elif verified >= MAX_VERIFY:
            r["not_verified"] = f"beyond the first {MAX_VERIFY} points that meet max_error: estimate only"
        else:
            verified += 1
            best = bests.get(r["family"])
            if best is c and c.checks.get("host") and "not_run" not in c.checks["host"]:
                _record(r, c.checks, alt_dir / r["family"], outdir)  # the family's best: already verified
            else:
                todo.append((r, c))
    for r, c in bar(todo, desc="verify the front", unit="point", disable=not progress, leave=False):
        work = outdir / FRONT_DIR / f"{r['family']}_{r['trial']:04d}"
        checks = {"host": verify_host(c.impl, work / "c")}
        for t in TARGETS:
            checks[t] = (verify_on_target(c.impl, t, work / "c", (work / t).resolve()) if t in c.impl.front_checked_on
                         else {"not_run": c.impl.front_not_checked_reason})
        _record(r, checks, work / "c", outdir)
    return {"cap": MAX_VERIFY, "meeting_max_error": sum(r["meets_max_error"] for r in rows), "verified": verified,
            "run_here": len(todo), "seconds": time.perf_counter() - t0}


def _record(row: dict, checks: dict, c_dir: Path, outdir: Path) -> None:
    row["checks"] = checks
    row["c_hash"] = checks["host"].get("c_hash")
    row["c_dir"] = Path(c_dir).resolve().relative_to(outdir.resolve()).as_posix()
    row["measured"] = {t: {"cycles": checks[t]["cycles"], "flash_bytes": checks[t]["flash_bytes"]}
                       for t in TARGETS if "cycles" in checks.get(t, {})}
    row["bit_exact"] = _checked(checks)
