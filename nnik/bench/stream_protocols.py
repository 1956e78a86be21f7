"""`make bench`, the sender's protocol: every shipped job through `nnik job`'s stages with ZVD at
1 kHz, galvo_cba2012 on the Uno and corexy_nonlinear on the Uno and the Mega (each with [dynamics] f_hz 40,
zeta 0.1, each job's build with the options its file uses), streamed both ways grbl senders
stream (grbl's wiki, "Interfacing with Grbl"): character counting within the firmware's receive
buffer, and send-response. Per job and protocol: the samples the chip computed too late
(missed_samples), the sample loop's CPU, its mean and worst cycles a sample, chip = model.

The trained models are nnik.bench.motion's (build/bench/motion/<scenario>/), or --model NAME=DIR.
Figures go to build/bench/stream_protocols.json.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

from rich.console import Console
from rich.table import Table

console = Console(highlight=False, width=None if sys.stdout.isatty() else 200)
DATASETS = Path(__file__).resolve().parents[2] / "datasets"
OUT = Path("build") / "bench"
MACHINES = (("galvo_cba2012", "atmega328p"), ("corexy_nonlinear", "atmega328p"), ("corexy_nonlinear", "atmega2560"))
DYNAMICS = {"f_hz": 40.0, "zeta": 0.1}
# the shipped jobs for these machines (servo_* and xy_table_reference are the DC-servo table's)
JOBS = ("circle", "fusion360_grbl", "grbl_cam_laser", "inkscape_gcodetools", "l_path", "lasergrbl_raster",
        "lightburn_grbl", "pen_plotter", "slicer_xy", "star")


def scenario_at_1khz(name: str):
    """The shipped scenario at 1 kHz with the [dynamics] that ZVD is designed for."""
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(DATASETS / f"{name}.toml")
    raw = dict(scn.raw)
    raw["motion"] = {**raw.get("motion", {}), "sample_hz": 1000}
    raw.setdefault("dynamics", dict(DYNAMICS))
    return _rewritten(scn, raw)


def _rewritten(scn, raw: dict):
    """A copy of the scenario's TOML with raw's [motion] and [dynamics], loaded."""
    import tempfile

    from nnik.machine.scenario import load_scenario

    text = Path(scn.source).read_text()
    lines, skip = [], False
    for ln in text.splitlines():
        head = ln.strip()
        if head.startswith("["):
            skip = head in ("[motion]", "[dynamics]")
        if not skip:
            lines.append(ln)
    for table in ("motion", "dynamics"):
        lines.append(f"[{table}]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in raw[table].items()]
    d = Path(tempfile.mkdtemp(prefix="nnik-stream-"))
    path = d / Path(scn.source).name
    path.write_text("\n".join(lines) + "\n")
    return load_scenario(path)


def run_job_both(model_dir: Path, scn, job: Path, mcu: str) -> dict:
    """The job's stages once, the chip built once, run with each protocol."""
    from nnik.firmware.gcode.chip import PROTOCOLS
    from nnik.firmware.model_dir import ModelDir
    from nnik.job import cosim
    from nnik.job.measure import compare_chip, measure
    from nnik.job.parse import JobRequest, parse
    from nnik.job.plan import plan
    from nnik.job.sample import sample
    from nnik.job.shape import shape

    model = ModelDir.load(model_dir)
    parsed = parse(JobRequest(job, scn, None, "zvd"))
    parsed = replace(parsed, cfg=replace(parsed.cfg, mcu=mcu))
    out = OUT / "stream_protocols" / f"{scn.name}-{mcu}"
    out.mkdir(parents=True, exist_ok=True)
    shaped = shape(plan(parsed), model.ik, out)
    measured = measure(sample(shaped, model.ik))
    built = cosim.build(model, shaped.cfg, out / "work" / job.stem, mcu)
    res = {"job_s": measured.seconds, "samples": measured.figures["motion"]["samples"]}
    for protocol in PROTOCOLS:
        co = cosim.run(built, shaped, measured.seconds, protocol=protocol)
        c = compare_chip(co, measured, out)
        res[protocol] = {k: c.get(k) for k in ("missed_samples", "cpu_sample_loop", "cycles_per_sample",
                                               "worst_sample_cycles", "steps_equal", "replies_equal", "tool_equal",
                                               "flash_bytes", "ram_bytes", "stream", "state")}
    return res


def main(argv=None) -> int:
    from nnik.bench.motion import trained

    ap = argparse.ArgumentParser(prog="python -m nnik.bench.stream_protocols", description=__doc__.split("\n")[0])
    ap.add_argument("--model", action="append", default=[], metavar="NAME=DIR", help="a trained model directory")
    ap.add_argument("--jobs", nargs="*", help="job stems (default: JOBS)")
    args = ap.parse_args(argv)
    dirs = dict(m.split("=", 1) for m in args.model)
    results: dict = {}
    for name, mcu in MACHINES:
        model_dir = Path(dirs[name]) if name in dirs else trained(name)
        scn = scenario_at_1khz(name)
        for stem in args.jobs or JOBS:
            job = DATASETS / "jobs" / f"{stem}.gcode"
            key = f"{name}@{mcu}/{job.stem}"
            console.print(f"[dim]{key} ...[/dim]")
            try:
                results[key] = run_job_both(model_dir, scn, job, mcu)
            except Exception as exc:  # a job this machine does not run (a servo table's): said, not measured
                results[key] = {"not_run": str(exc).splitlines()[0][:160]}
    t = Table(title="Missed samples and the sample loop's CPU by the sender's protocol (ZVD, 1 kHz)")
    for col in ("machine / job", "job time (s)", "protocol", "missed", "CPU", "cycles a sample: mean (worst)",
                "chip = model", "flash / RAM (B)"):
        t.add_column(col)
    for key, r in results.items():
        if "not_run" in r:
            t.add_row(key, "-", "-", "-", "-", "-", r["not_run"][:60], "-")
            continue
        for protocol in ("counting", "send-response"):
            c = r[protocol]
            same = c["steps_equal"] and c["replies_equal"] and c["tool_equal"] is not False
            t.add_row(key, f"{r['job_s']:.2f}", protocol, str(c["missed_samples"]),
                      f"{100 * c['cpu_sample_loop']:.1f} %" if c["cpu_sample_loop"] is not None else "-",
                      f"{c['cycles_per_sample']['mean']:.0f} ({c['worst_sample_cycles']})" if c["cycles_per_sample"]
                      else "-", "yes" if same else "NO", f"{c['flash_bytes']} / {c['ram_bytes']}")
    console.print(t)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "stream_protocols.json").write_text(json.dumps(results, indent=2) + "\n")
    return differ(results)


def differ(results: dict) -> int:
    """1 (and the jobs said) where the chip's steps or answers differ from the model's."""
    bad = [k for k, r in results.items() if "not_run" not in r
           and not all(r[p]["steps_equal"] and r[p]["replies_equal"] for p in ("counting", "send-response"))]
    if bad:
        console.print(f"[red]chip differs from the model: {', '.join(bad)}[/red]")
    return int(bool(bad))


if __name__ == "__main__":
    sys.exit(main())
