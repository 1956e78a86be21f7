"""The closed-loop report of `nnik run` on a DC-servo xy_table: OUTDIR/report/closed_loop.md, a
table per test comparing the controllers (overshoot, settling time, steady-state error, contour
error max and RMS, the contour error at reversals, duty saturation, a neural controller's weight
clamps / updates), the identified models, the tuned gains and the neural controllers' pretraining,
the default controller and why (scored on the identified plant), the per-test pictures
(OUTDIR/job/TEST_KIND.png), the chip's figures, and the honest comparison's tables and learning
curves (nnik.job.servo_compare: report/compare.md, its PNGs beside this file).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from nnik.files.atomic_write import write_file_atomic
from nnik.job.servo_compare import DIVERGED_PID_FACTOR  # a contour error past 10x the tuned PID's: diverged

HEADER = ("controller", "contour max um", "contour RMS um", "at reversals um", "overshoot um", "settling s",
          "steady-state um", "saturated %", "clamps / updates")


def _fmt(v, spec: str = ".1f") -> str:
    return "-" if v is None else format(v, spec)


def row(kind: str, r: dict, pid_max: float | None = None) -> tuple[str, ...]:
    """pid_max: the tuned PID's largest contour error on the same job (a learning controller past
    DIVERGED_PID_FACTOR times it is flagged diverged, as past 1 % clamps)."""
    steps = r["steps"]
    settle = [s["settling_s"] for s in steps]
    return (kind, _fmt(r["contour_um"]["max_um"]), _fmt(r["contour_um"]["rms_um"]), _fmt(r["reversals"]["max_um"]),
            _fmt(max((s["overshoot_um"] for s in steps), default=None)),
            "-" if not steps else ("not settled" if None in settle else _fmt(max(settle), ".3f")),
            _fmt(max((s["steady_state_um"] for s in steps), default=None)), _fmt(100 * r["saturated_fraction"]),
            _learning(r.get("learning"), pid_max is not None and r["contour_um"]["max_um"] > DIVERGED_PID_FACTOR * pid_max))


def _learning(lr: dict | None, past_pid: bool) -> str:
    if lr is None:
        return "-"
    return f"{lr['clamps']} / {lr['updates']}" + (" **diverged**" if lr["diverged"] or past_pid else "")


def table(results: dict) -> list[str]:
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    pid_max = results["pid"]["contour_um"]["max_um"] if "pid" in results else None
    return lines + ["| " + " | ".join(row(k, r, pid_max)) + " |" for k, r in results.items()]


def _gains_line(kind: str, g: dict) -> str:
    if "w1" not in g:
        return f"- {kind}: `{json.dumps(g)}`"
    return (f"- {kind}: pretrained integer weights (`servo/gains.json`), eta_shift {g['eta_shift']}, in_shift "
            f"{g['in_shift']}, Jacobian (Q12) {g['jacobian']}")


def _pretraining(logs: dict) -> list[str]:
    lines = ["", "Pretrained on the identified models (the seed's steps and the reference job, the same integer "
             "controller learning online, the weights carried from episode to episode; log: `servo/pretrain.json`):", ""]
    for k, lg in logs.items():
        state = (f"below 2 % of the reference after {lg['episodes']} episode{'s' * (lg['episodes'] != 1)}" if lg["passed"] else
                 f"**not** below 2 % of the reference within {lg['episode_budget']} episodes")
        lines.append(f"- {k}: {state} (eta_shift {lg['eta_shift']}, in_shift {lg['in_shift']}); from power-on, worst "
                     f"error / (2 % of the reference) {lg['verify_worst']:.2f}; "
                     f"impulse Jacobian X {lg['jacobian'][0]:.4f}, Y {lg['jacobian'][1]:.4f} (the seed's rig: "
                     f"X 1.0103, Y 0.6047)")
    return lines


def _compare(cmp: dict, md: Path) -> list[str]:
    """The comparison's markdown (its headings one level down, its PNG links from this file)."""
    text = Path(cmp["markdown"]).read_text()
    rel = os.path.relpath(Path(cmp["markdown"]).parent, md.parent)
    if rel != ".":
        text = text.replace("](", f"]({rel}/")
    return ["", *("#" + ln if ln.startswith("#") else ln for ln in text.splitlines())]


def write_report(out: Path, scn, fits, gains: dict, best: str, results: dict, chip: dict, nn: dict) -> Path:
    """nn: {"why": the default's reason, "scores": kind -> its figures on the identified plant,
    "pretrain": kind -> the pretraining's log, "compare": nnik.job.servo_compare.compare's result}."""
    md = out / "report" / "closed_loop.md"
    md.parent.mkdir(parents=True, exist_ok=True)
    lines = [f"# {scn.name}: closed loop", "",
             f"Identified from the seed's excitation on the scenario's plant (`{scn.source}`):", ""]
    lines += [f"- {f.axis}: K {f.model.k_counts_s_v:.5g} counts/s/V, tau {f.model.tau_s:.4g} s (95 % CI "
              f"{f.model.tau_ci[0]:.4g} – {f.model.tau_ci[1]:.4g} s)" for f in fits]
    lines += ["", "Tuned against the identified models (gains: `servo/gains.json`):", ""]
    lines += [_gains_line(k, g) for k, g in gains.items()]
    lines += _pretraining(nn["pretrain"])
    lines += ["", f"Default controller: **{best}**: {nn['why']}. On the identified plant (the speed models "
              "and their Coulomb friction: what a real rig gives), RMS contour error as tuning measures it (to the "
              "path's pieces within +-0.5 s of each tick: a lag along the path counts), and in brackets the "
              "distance to the whole path (the tables' measure, blind to a lag): "
              + ", ".join(f"{k} {s['rms_um']:.1f} um ({s['path_rms_um']:.1f})" + (" diverged" if s["diverged"] else "")
                          for k, s in nn["scores"].items())
              + ". The tables below are on the scenario's true plant.", "",
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
        lines += ["## On the simulated Uno", "", "Each controller's C on the ATmega328P (simavr), closed loop with the "
                  "plant, its duty checked against the integer model tick by tick. Cycles: the controller's own "
                  "computation (the busy pin), and the tick's whole load with every encoder interrupt.", "",
                  "| controller | test | mismatch | controller cycles/tick max | tick + encoder cycles max | CPU % max |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {k} | {j} | {c['mismatches']} | {c['controller_cycles_max']} | {c['tick_cycles_max']} | "
                  f"{c['cpu_pct_max']:.1f} |" for k, per in chip.items() for j, c in per.items()]
    lines += _compare(nn["compare"], md)
    write_file_atomic(md, "\n".join(lines) + "\n")
    return md
