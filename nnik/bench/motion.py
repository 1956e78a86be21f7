"""`make bench`, the motion part (issue 18): the G-code firmware with its planner, sampler and
input shaper on the simulated Uno, for galvo_cba2012 and corexy_nonlinear, without a shaper
and with ZVD at 40 Hz, zeta 0.1 (both axes), on the shipped jobs (L path, circle, star).

Per build: flash and SRAM (.data + .bss, avr-size) of the G-code sketch, the shaper's buffers,
the self-test's pass; per job: the job's time, the peak step rate against the one-step-per-tick
limit, the sample loop's share of the CPU (the busy pin D8 high over the motion's time, on
simavr), busy cycles per sample, and whether every step equals the Python model's.
The trained models are cached in build/bench/motion/<scenario>/ (generate, train, evaluate as
the tests do). Figures go to build/bench/motion.json too.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from nnik import pipeline
from nnik.firmware.config import default_machine, shaper_taps
from nnik.machine.scenario import load_scenario

console = Console(highlight=False, width=None if sys.stdout.isatty() else 200)
DATASETS = Path(__file__).resolve().parents[2] / "datasets"
OUT = Path("build") / "bench"
SCENARIOS = ("galvo_cba2012", "corexy_nonlinear")
JOBS = ("l_path", "circle", "star")
ZVD = {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)}


def trained(name: str) -> Path:
    out = OUT / "motion" / name
    if not (out / pipeline.MODEL_FILE).is_file():
        scn = load_scenario(DATASETS / f"{name}.toml")
        pipeline.generate(scn, out)
        pipeline.train(scn, out, progress=False)
        pipeline.evaluate(out)
    pipeline.export(out)
    return out


def machines(scn, plan_blocks: int, sample_hz: int = 1000) -> dict:
    """No shaper and ZVD 40 Hz; the max feed is capped where the planner's speeds must stay below
    256 um per sample (7,679 mm/min at 500 Hz)."""
    base = default_machine(scn, "none")
    top = ((1 << 24) - 1) * 60 * sample_hz // 65536 // 1000 * 1000
    base = replace(base, plan_blocks=plan_blocks, sample_hz=sample_hz, max_feed_um_min=min(base.max_feed_um_min, top))
    return {"none": base, "zvd": replace(base, shaper="zvd", shaper_taps=shaper_taps("zvd", ZVD, base.sample_hz))}


def run_one(run: Path, cfg, work: Path, jobs=JOBS) -> dict:
    from nnik.firmware.arduino import export_arduino
    from nnik.firmware.gcode import chip
    from nnik.firmware.gcode.chip import CLOCK_HZ
    from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
    from nnik.firmware.gcode.reader import sendable
    from nnik.job.measure import cpu_report, missed_samples, motion_report
    from nnik.firmware.gcode.motion import interpret, plan_steps
    from nnik.firmware.gcode.steps import chip_events, model_events
    from nnik.firmware.ik_oracle import ik_oracle

    lib = export_arduino(run, work / "lib", cfg)
    name = lib["name"]
    st = chip.run_firmware(chip.build_sketch(work / "lib", f"{name}_selftest", work / "build"), [], work / "build", 5.0)
    fw = chip.build_sketch(work / "lib", f"{name}_gcode", work / "build", chip.file_run_defines(cfg))
    ik = ik_oracle(run)
    out = {"flash_bytes": fw.flash_bytes, "ram_bytes": fw.ram_bytes, "shaper_ram_bytes": cfg.shaper_ram_bytes,
           "selftest": next((t for _, t in st.replies if t.startswith(("PASS", "FAIL"))), "no answer"), "jobs": {}}
    for job in jobs:
        path = DATASETS / "jobs" / f"{job}.gcode"
        # the lines as `nnik job` sends them (prepared for the flavour, text): the same chip input
        lines = [sendable(ln).decode("latin-1") for ln in prepare(read_job(path), cfg, JobOptions(), str(path)).lines]
        plan = interpret(lines, cfg)
        seg = plan_steps(plan, cfg, ik)
        res = chip.run_firmware(fw, lines, work / "build", 2.0 + 1.5 * seg.ticks.sum() / cfg.tick_hz)
        got, want = chip_events(res.steps, res.marks, CLOCK_HZ // cfg.tick_hz), model_events(seg)
        busy = (res.busy[:, 1] - res.busy[:, 0]).astype(np.float64)
        m = motion_report(seg, cfg)
        out["jobs"][job] = {**{k: m[k] for k in ("job_s", "samples", "peak_step_rate_hz", "step_rate_limit_hz",
                                                 "overspeed_samples")},
                            **cpu_report(res, busy, m["samples"]),
                            "missed_samples": missed_samples(res.marks, seg, CLOCK_HZ // cfg.tick_hz),
                            "steps": int(len(want)), "segments": int(len(seg.ticks)),
                            "steps_equal": bool(got.shape == want.shape and np.array_equal(got, want)
                                                and len(res.marks) == len(seg.ticks))}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.motion", description=__doc__.split("\n")[0])
    ap.add_argument("--plan-blocks", type=int, nargs="+", default=[8, 16], help="planner queues to build (RAM)")
    ap.add_argument("--sample-hz", type=int, nargs="+", default=[1000, 500], help="sample rates to run the jobs at")
    args = ap.parse_args(argv)
    results = {}
    for name in SCENARIOS:
        run = trained(name)
        scn = load_scenario(DATASETS / f"{name}.toml")
        for hz in args.sample_hz:
            for n in args.plan_blocks if hz == args.sample_hz[0] else args.plan_blocks[:1]:
                for kind, cfg in machines(scn, n, hz).items():
                    key = f"{name}/{kind}/{hz} Hz/N{n}"
                    jobs = JOBS if n == args.plan_blocks[0] else ()
                    console.print(f"[dim]{key} ...[/dim]")
                    results[key] = run_one(run, cfg, OUT / "motion" / "work" / f"{name}_{kind}_{hz}_{n}", jobs)
    t = Table(title="G-code firmware with the planner and the input shaper on the simulated Uno (16 MHz)")
    for col in ("scenario / shaper / samples / queue", "job", "job time (s)", "peak step rate / limit (Hz)", "sample loop CPU",
                "cycles/sample (worst)", "missed samples", "steps equal", "flash / SRAM (B)", "shaper SRAM (B)", "self-test"):
        t.add_column(col)
    for key, r in results.items():
        rows = r["jobs"].items() or [("-", None)]
        for job, j in rows:
            t.add_row(key, job, f"{j['job_s']:.3f}" if j else "-",
                      f"{j['peak_step_rate_hz']:.0f} / {j['step_rate_limit_hz']}" if j else "-",
                      f"{100 * j['cpu_sample_loop']:.1f} %" if j and "cpu_sample_loop" in j else "-",
                      f"{j['cycles_per_sample']['mean']:.0f} ({j.get('worst_sample_cycles', '-')})" if j else "-",
                      str(j["missed_samples"]) if j else "-",
                      ("yes" if j["steps_equal"] else "NO") if j else "-",
                      f"{r['flash_bytes']} / {r['ram_bytes']}", str(r["shaper_ram_bytes"]), r["selftest"][:24])
    console.print(t)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "motion.json").write_text(json.dumps(results, indent=2) + "\n")
    bad = [k for k, r in results.items() if any(not j["steps_equal"] for j in r["jobs"].values())]
    if bad:
        console.print(f"[red]steps differ from the Python model: {', '.join(bad)}[/red]")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
