"""The honest comparison (issue 29, item 7): every controller against every plant on every shipped
closed-loop test, in Python (the controller's integer model against the plant, as
nnik.dynamics.servo.closed_loop.simulate runs it), under the same limits (duty +-duty_max, the
same tick and encoder).

Plants (nnik.dynamics.servo.drift):
- nominal:   the scenario's plant (what the identified models were fitted to);
- drift:     the scenario's plant drifting over each job (load +50 %, friction x2, supply -20 %,
             ramped in drift.PIECES pieces: nominal in the first, fully drifted in the last);
- differing: the scenario's plant with J x1.4, Ra x1.2, friction x1.5, Ke x0.9 from the start.
Every controller starts each job from power-on (reset(): the neural ones from their pretrained
weights) and the neural ones learn online throughout.

Measures (nnik.job.servo_measure, on the carriage's true position): contour error max and RMS
(the distance to the whole path: blind to a lag along it), the tracking error's RMS (the distance
to the tick's reference point, both axes: what a lag costs), the largest contour error near a
reversal, the steady-state error (the largest over the job's steps), the share of saturated
ticks; for the neural controllers the weight clamps and updates.
A neural controller's run is flagged `diverged` (issue 29 item 4) when its clamps pass 1 % of its
updates ("clamps"), or when its largest contour error passes 10x the tuned PID's largest on the
same job and plant, the PID's taken as at least one encoder count (a single-axis step's contour
error is 0 for a PID that neither overshoots nor leaves the line) ("10x pid"). The baselines do
not learn: no flag.

Output: OUT/compare.md (one table per job: plant x controller, and the headline: who has the
lowest RMS contour error per job and plant, and where a baseline beats both neural controllers),
OUT/compare.json (every figure) and, per neural controller and job, a learning-curve PNG: the
contour error and the weight norm against time on each plant (the tuned PID's error beside it).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.files.atomic_write import replacing, write_file_atomic
from nnik.implementations.servo import BASELINES, NEURAL, make
from nnik.job.servo_loop import DIVERGED_CLAMP_FRACTION as DIVERGED_CLAMP_SHARE  # clamps > 1 % of updates

PLANTS = ("nominal", "drift", "differing")
METRICS = (("contour_rms_um", "rms_um"), ("tracking_rms_um", "tracking_um"), ("steady_state_um", "steady_um"))
DIVERGED_PID_FACTOR = 10.0


def make_plant(name: str, cfg, ticks: int, start: tuple[int, int]):
    from nnik.dynamics.servo.drift import JOB_DRIFT, PIECES, DriftPlant, differing
    from nnik.dynamics.servo.plant import Plant

    if name == "nominal":
        return Plant(cfg, start)
    if name == "drift":
        return DriftPlant(cfg, ticks, JOB_DRIFT, PIECES, start)
    if name == "differing":
        return Plant(differing(cfg), start)
    raise NnikError(f"unknown plant {name!r} (known: {', '.join(PLANTS)})")


def run_one(kind: str, gains: dict, cfg, ref, plant_name: str) -> tuple[dict, dict]:
    """(figures, curves) of one controller on one plant over one Reference."""
    from nnik.dynamics.servo.closed_loop import simulate
    from nnik.job.servo_measure import measure

    ctl = make(kind, gains, cfg)
    counts = np.asarray(ref.counts)
    start = tuple(int(c) for c in counts[0])
    norms = np.zeros(len(counts))
    norm = getattr(ctl, "weight_norm", None)

    def after(k: int) -> None:
        norms[k] = norm()

    trace = simulate(cfg, ctl, counts, plant=make_plant(plant_name, cfg, len(counts), start),
                     after_tick=after if norm else None)
    fig, contour = measure(ref, trace)
    steady = [s["steady_state_um"] for s in fig["steps"]]
    clamps, updates = int(getattr(ctl, "clamps", 0)), int(getattr(ctl, "updates", 0))
    out = {"contour_max_um": fig["contour_um"]["max_um"], "contour_rms_um": fig["contour_um"]["rms_um"],
           "reversal_max_um": fig["reversals"]["max_um"], "steady_state_um": max(steady) if steady else None,
           "tracking_rms_um": float(np.hypot(fig["tracking_um"]["x"]["rms_um"], fig["tracking_um"]["y"]["rms_um"])),
           "saturated_fraction": fig["saturated_fraction"], "final_error_um": fig["final_error_um"],
           "clamps": clamps, "updates": updates,
           "clamp_share": clamps / updates if updates else 0.0}
    return out, {"contour_um": contour, "weight_norm": norms if norm else None}


def diverged(r: dict, pid: dict | None, um_per_count: float) -> str | None:
    """Why a neural run is flagged diverged ("clamps", "10x pid"), or None."""
    if r["clamp_share"] > DIVERGED_CLAMP_SHARE:
        return "clamps"
    if pid is not None and r["contour_max_um"] > DIVERGED_PID_FACTOR * max(pid["contour_max_um"], um_per_count):
        return "10x pid"
    return None


def compare(scn, gains: dict, out_dir: Path, say=print, jobs=None, plants=PLANTS, preamble=(), models=None) -> dict:
    """Run every controller in `gains` (kind -> gains, or params for a neural one) on every plant and
    job (paths; default: every datasets/jobs/servo_*.gcode and the reference job); write
    OUT/compare.md (the identified `models`' impulse Jacobians beside the seed's when given, then
    `preamble`: markdown lines before its tables), compare.json and the learning curves. Returns
    {"results": job -> plant -> kind -> figures, "headline": [...], "markdown":
    path, "figures": [png paths]}."""
    from nnik.job.parse import JobRequest
    from nnik.job.reference import job_reference

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    cfg = scn.servo
    jobs = list(jobs) if jobs is not None else default_jobs()
    kinds = [k for k in (*BASELINES, *NEURAL) if k in gains]
    results, pngs = {}, []
    for job in jobs:
        _, ref = job_reference(JobRequest(Path(job), scn))
        name = Path(job).name
        results[name], learning = {}, {}
        for plant in plants:
            row, curves = {}, {}
            for kind in kinds:
                row[kind], curves[kind] = run_one(kind, gains[kind], cfg, ref, plant)
            for kind in kinds:
                pid = row.get("pid")
                row[kind]["diverged"] = diverged(row[kind], pid, cfg.um_per_count) if kind in NEURAL else None
                if curves[kind]["weight_norm"] is not None:
                    learning.setdefault(kind, {})[plant] = (curves[kind], curves.get("pid"))
            results[name][plant] = row
            say(f"compare {name} on the {plant} plant: " + ", ".join(
                f"{k} {row[k]['contour_rms_um']:.1f}" for k in kinds) + " um RMS contour")
        for kind, by_plant in learning.items():
            pngs.append(learning_curve(out_dir / f"learning_{Path(name).stem}_{kind}.png",
                                       f"{kind} on {name}: learning online", by_plant, ref.tick_s))
    headline = headlines(results)
    md = out_dir / "compare.md"
    pre = (jacobian_lines(models, cfg) + [""] if models is not None else []) + [x for p in preamble for x in (p, "")]
    write_file_atomic(md, markdown(results, headline, pngs, out_dir, pre))
    write_file_atomic(out_dir / "compare.json", json.dumps({"results": results, "headline": headline}, indent=2) + "\n")
    return {"results": results, "headline": headline, "markdown": str(md), "figures": [str(p) for p in pngs]}


def jacobian_lines(models, cfg) -> list[str]:
    """The identified models' impulse Jacobians beside the seed's (its rig), as a markdown table."""
    from nnik.implementations.servo.nn.jacobian import SEED_JACOBIANS, impulse_jacobian

    lines = ["Plant Jacobians by the seed's impulse method (normalised to 12 V and 40 mm, per volt-second; "
             "nnik.implementations.servo.nn.jacobian):", "",
             "| axis | identified K counts/s/V | ours 1/s | seed's rig |",
             "|---|---|---|---|"]
    for axis, m, seed in zip("XY", models, SEED_JACOBIANS):
        lines.append(f"| {axis} | {m.k_counts_s_v:.5g} | {impulse_jacobian(m, cfg):.4f} | {seed:.4f} |")
    return lines


def default_jobs() -> list[Path]:
    jobs = Path(__file__).resolve().parents[2] / "datasets" / "jobs"
    return sorted(jobs.glob("servo_*.gcode")) + [jobs / "xy_table_reference.gcode"]


def _best(row: dict, kinds, key: str) -> str | None:
    have = [k for k in row if k in kinds and row[k][key] is not None]
    return min(have, key=lambda k: row[k][key]) if have else None


def _wins(b: float, n: float) -> str:
    return "yes" if b < n else "no" if n < b else "tie"


def headlines(results: dict) -> list[dict]:
    """Per job and plant, by RMS contour error, RMS tracking error and (where the job has steps)
    steady-state error:
    the best controller, the best baseline and the best neural one, and whether a baseline wins
    ("yes", "no", "tie"; when both kinds ran)."""
    out = []
    for job, by_plant in results.items():
        for plant, row in by_plant.items():
            best = _best(row, row, "contour_rms_um")
            h = {"job": job, "plant": plant, "best": best, "best_rms_um": row[best]["contour_rms_um"]}
            for key, tag in METRICS:
                b, n = _best(row, BASELINES, key), _best(row, NEURAL, key)
                if b:
                    h[f"baseline_{tag}"] = [b, row[b][key]]
                if n:
                    h[f"neural_{tag}"] = [n, row[n][key]]
                if b and n:
                    h[f"baseline_wins_{tag}"] = _wins(row[b][key], row[n][key])
            out.append(h)
    return out


def _f(v, nd=1) -> str:
    return "–" if v is None else f"{v:.{nd}f}"


def _flag(kind: str, why: str | None) -> str:
    return "–" if kind not in NEURAL else f"**yes** ({why})" if why else "no"


def markdown(results: dict, headline: list[dict], pngs: list[Path], out_dir: Path, preamble=()) -> str:
    lines = ["# Neural controllers against the tuned baselines", "",
             "Python integer models against the plant; contour errors in µm on the carriage's true position. "
             "`diverged` (neural controllers): clamps over 1 % of updates, or a largest contour error over 10x the "
             "tuned PID's (at least one count) on the same job and plant.", "",
             *preamble, "## Headline", "",
             "RMS contour error, RMS tracking error and, on jobs with steps, the steady-state error (the largest "
             "over the steps), µm: the best baseline against the best neural controller, and whether the baseline "
             "wins.", "",
             "| job | plant | best (RMS contour) | contour: baseline | neural | wins | tracking: baseline | neural "
             "| wins | steady state: baseline | neural | wins |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def pair(h, key):
        return f"{h[key][0]} ({_f(h[key][1])})" if key in h else "–"

    for h in headline:
        cells = [f"{pair(h, 'baseline_' + t)} | {pair(h, 'neural_' + t)} | {h.get('baseline_wins_' + t, '–')}"
                 for _, t in METRICS]
        head = f"| {h['job']} | {h['plant']} | {h['best']} ({_f(h['best_rms_um'])}) | "
        lines.append(head + " | ".join(cells) + " |")
    for job, by_plant in results.items():
        lines += ["", f"## {job}", "",
                  "| plant | controller | contour max | contour RMS | tracking RMS | at reversals | steady state "
                  "| saturated % | clamps / updates | diverged |", "|---|---|---|---|---|---|---|---|---|---|"]
        for plant, row in by_plant.items():
            for kind, r in row.items():
                lines.append(f"| {plant} | {kind} | {_f(r['contour_max_um'])} | {_f(r['contour_rms_um'])} | "
                             f"{_f(r['tracking_rms_um'])} | "
                             f"{_f(r['reversal_max_um'])} | {_f(r['steady_state_um'])} | "
                             f"{100 * r['saturated_fraction']:.1f} | {r['clamps']} / {r['updates']} | "
                             f"{_flag(kind, r['diverged'])} |")
    if pngs:
        lines += ["", "## Learning curves", ""]
        lines += [f"![{Path(p).stem}]({Path(p).relative_to(out_dir)})" for p in pngs]
    return "\n".join(lines) + "\n"


def learning_curve(path: Path, title: str, by_plant: dict, tick_s: float) -> Path:
    """Contour error (with the tuned PID's beside it) and weight norm against time, one column per plant."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, len(by_plant), figsize=(4.6 * len(by_plant), 6), squeeze=False, sharex="col")
    for c, (plant, (cur, pid)) in enumerate(by_plant.items()):
        t = np.arange(len(cur["contour_um"])) * tick_s
        if pid is not None:
            ax[0, c].plot(t, pid["contour_um"], color="0.6", lw=0.7, label="pid (tuned)")
        ax[0, c].plot(t, cur["contour_um"], "r-", lw=0.7, label="neural")
        ax[0, c].set(title=f"{plant} plant", ylabel="contour error µm")
        ax[0, c].legend(fontsize=7)
        ax[1, c].plot(t, cur["weight_norm"], "b-", lw=0.8)
        ax[1, c].set(xlabel="s", ylabel="weight norm")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as tmp:
        fig.savefig(tmp, dpi=80)
    plt.close(fig)
    return path
