"""`make bench`, the speed of `nnik job`: a long job through the Python model alone
(`nnik job --no-chip`) and through the model and the simulated Uno (`nnik job`), side by side in
one run, each timed over the whole command (start-up, imports, builds, simavr, the comparison,
the plot and the JSON). Printed per run: the job's seconds of motion, the command's wall seconds
and their ratio (times real time) against the issue's targets (model >= 100x, chip >= 4x), and
for the chip the simulated cycles per wall second; and the model's run_job timed inside one
process after its imports (torch, the pipeline, matplotlib: about 2 s of every command). The job is nnik.bench.longjob's raster
(deterministic: 75 rows of 100 mm, about 305 s of motion) unless paths are given; the model is
galvo_cba2012's `nnik run`, cached in build/bench/job_speed/. Figures also go to
build/bench/job_speed.json.

    python -m nnik.bench.job_speed [JOB.gcode ...] [--outdir MODEL_DIR] [--mcu atmega2560] [--photo]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from nnik.bench.longjob import raster, write

console = Console(highlight=False, width=None if sys.stdout.isatty() else 200)
DATASETS = Path(__file__).resolve().parents[2] / "datasets"
OUT = Path("build") / "bench" / "job_speed"
TARGETS = {"model": 100.0, "chip": 4.0}


def model_dir(outdir: Path | None) -> Path:
    """The scenario's finished `nnik run` (the job runs only the verified pick), made once."""
    out = Path(outdir) if outdir else OUT / "galvo_cba2012"
    if not (out / "pick.json").is_file():
        if outdir:
            raise SystemExit(f"{out}: no finished `nnik run` (pick.json)")
        subprocess.run([sys.executable, "-m", "nnik", "run", str(DATASETS / "galvo_cba2012.toml"), "-o", str(out)],
                       check=True, stdout=subprocess.DEVNULL)
    return out


def timed_job(out: Path, job: Path, chip: bool, mcu: str) -> dict:
    """One `nnik job` command, timed from start to exit; its JSON's figures."""
    cmd = [sys.executable, "-m", "nnik", "job", str(out), str(job)]
    cmd += ["--mcu", mcu] if chip else ["--no-chip"]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "COLUMNS": "200"})
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{r.stderr[-2000:]}")
    res = json.loads((out / "job" / f"{job.stem}.json").read_text())
    row = {"job": job.name, "run": "chip" if chip else "model", "job_s": res["motion"]["job_s"], "wall_s": wall,
           "samples": res["motion"]["samples"], "steps": res["steps"]}
    row["ratio"] = row["job_s"] / wall
    if chip:
        c = res["chip"]
        row.update(mcu=mcu, cycles=c["end_cycle"], cycles_per_s=c["end_cycle"] / wall, steps_equal=c["steps_equal"],
                   replies_equal=c["replies_equal"], tool_equal=c["tool_equal"])
    else:
        row["samples_per_s"] = row["samples"] / wall
    return row


def in_process(out: Path, job: Path) -> dict:
    """The Python model's run_job timed inside one process after its imports (torch, the
    pipeline, matplotlib): the share of the command that is the model's own work."""
    code = ("import json, sys, time; from pathlib import Path; import nnik.pipeline, nnik.firmware.gcode.plot; "
            "from nnik.job.open_loop import run_job; t = time.perf_counter(); "
            "r = run_job(Path(sys.argv[1]), Path(sys.argv[2]), use_chip=False); "
            "print(json.dumps([time.perf_counter() - t, r['motion']['job_s'], r['motion']['samples']]))")
    r = subprocess.run([sys.executable, "-c", code, str(out), str(job)], capture_output=True, text=True, check=True)
    wall, job_s, samples = json.loads(r.stdout.strip().splitlines()[-1])
    return {"job": job.name, "run": "model, after imports", "job_s": job_s, "wall_s": wall, "samples": samples,
            "ratio": job_s / wall, "samples_per_s": samples / wall}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m nnik.bench.job_speed", description=__doc__.splitlines()[0])
    p.add_argument("jobs", nargs="*", help="G-code files (default: the generated 305 s raster)")
    p.add_argument("--outdir", help="a finished `nnik run` directory (default: galvo_cba2012's, made once)")
    p.add_argument("--mcu", default="atmega328p", choices=("atmega328p", "atmega2560"))
    p.add_argument("--photo", action="store_true",
                   help="also a 101,184-line photo engraving (ordered dither, a line per pixel; 458 s of motion)")
    a = p.parse_args(argv)
    out = model_dir(a.outdir)
    jobs = [Path(j) for j in a.jobs] or [write(OUT / "raster.gcode", raster())]
    if a.photo:
        jobs.append(write(OUT / "photo.gcode", raster(225, 50.0, 0.1, pitch=0.1, dither=True)))
    rows = []
    for job in jobs:
        for chip in (False, True):
            rows.append(timed_job(out, job, chip, a.mcu))
        rows.append(in_process(out, job))
    t = Table(title="nnik job: seconds of motion per wall second, the whole command (times real time)")
    for h in ("job", "run", "job s", "wall s", "ratio", "target", "rate", "every step equal"):
        t.add_column(h, justify="left" if h in ("job", "run") else "right")
    for r in rows:
        tgt = TARGETS.get(r["run"])
        rate = (f"{r['cycles_per_s'] / 1e6:.0f} M cycles/s" if r["run"] == "chip"
                else f"{r['samples_per_s'] / 1e3:.0f} k samples/s")
        eq = ("yes" if r["steps_equal"] and r["replies_equal"] and r["tool_equal"] else "NO") if r["run"] == "chip" else "-"
        t.add_row(r["job"], f"chip ({r['mcu']})" if r["run"] == "chip" else r["run"], f"{r['job_s']:.1f}",
                  f"{r['wall_s']:.1f}", f"{r['ratio']:.1f}x", f">= {tgt:g}x {'met' if r['ratio'] >= tgt else 'NOT met'}" if tgt else "-",
                  rate, eq)
    console.print(t)
    (OUT.parent / "job_speed.json").parent.mkdir(parents=True, exist_ok=True)
    (OUT.parent / "job_speed.json").write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
