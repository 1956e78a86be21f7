"""The closed-loop report of `nnik run` on a DC-servo xy_table: OUTDIR/report/closed_loop.md, a
table per test comparing the controllers (overshoot, settling time, steady-state error, contour
error max and RMS, the contour error at reversals, duty saturation), the identified models, the
tuned gains, the default controller and why, and the per-test pictures (OUTDIR/job/TEST_KIND.png).
"""

from __future__ import annotations

import os
from pathlib import Path

from nnik.files.atomic_write import write_file_atomic

HEADER = ("controller", "contour max um", "contour RMS um", "at reversals um", "overshoot um", "settling s",
          "steady-state um", "saturated %")


def _fmt(v, spec: str = ".1f") -> str:
    return "-" if v is None else format(v, spec)


def row(kind: str, r: dict) -> tuple[str, ...]:
    steps = r["steps"]
    settle = [s["settling_s"] for s in steps]
    return (kind, _fmt(r["contour_um"]["max_um"]), _fmt(r["contour_um"]["rms_um"]), _fmt(r["reversals"]["max_um"]),
            _fmt(max((s["overshoot_um"] for s in steps), default=None)),
            "-" if not steps else ("not settled" if None in settle else _fmt(max(settle), ".3f")),
            _fmt(max((s["steady_state_um"] for s in steps), default=None)), _fmt(100 * r["saturated_fraction"]))


def table(results: dict) -> list[str]:
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    return lines + ["| " + " | ".join(row(k, r)) + " |" for k, r in results.items()]


def write_report(out: Path, scn, fits, gains: dict, best: str, results: dict, chip: dict) -> Path:
    md = out / "report" / "closed_loop.md"
    md.parent.mkdir(parents=True, exist_ok=True)
    lines = [f"# {scn.name}: closed loop", "",
             f"Identified from the seed's excitation on the scenario's plant (`{scn.source}`):", ""]
    lines += [f"- {f.axis}: K {f.model.k_counts_s_v:.5g} counts/s/V, tau {f.model.tau_s:.4g} s (95 % CI "
              f"{f.model.tau_ci[0]:.4g} – {f.model.tau_ci[1]:.4g} s)" for f in fits]
    lines += ["", "Tuned against the identified models (gains: `servo/gains.json`):", ""]
    lines += [f"- {k}: {g}" for k, g in gains.items()]
    ref_job = list(results)[-1]
    lines += ["", f"Default controller: **{best}**, the lowest RMS contour error on `{ref_job}` "
              f"({results[ref_job][best]['contour_um']['rms_um']:.1f} um) on the true plant.", "",
              "Overshoot, settling (the last time outside +-2 % of the step, at least 2 counts) and steady-state "
              "error are the worst over a test's steps; the contour error is the distance to the reference path; "
              "'at reversals' is the largest contour error within 0.25 s of a reference axis' reversal.", ""]
    for job, per in results.items():
        r0 = next(iter(per.values()))
        lines += [f"## {job} ({r0['reference']['seconds']:.2f} s, {r0['reference']['steps']} raw steps)", ""]
        lines += table(per)
        lines += [""] + [f"![{job} {k}]({os.path.relpath(r['png'], md.parent)})" for k, r in per.items()] + [""]
    if "not_run" in chip:
        lines += [f"Chip: not run ({chip['not_run']})."]
    else:
        lines += [f"## {best} on the simulated Uno", "", "| test | mismatch | controller cycles/tick max | "
                  "tick cycles max |", "|---|---|---|---|"]
        lines += [f"| {j} | {c['mismatches']} | {c['controller_cycles_max']} | {c['tick_cycles_max']} |"
                  for j, c in chip.items()]
    write_file_atomic(md, "\n".join(lines) + "\n")
    return md
