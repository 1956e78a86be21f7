"""`python -m nnik.bench.sample_profile MODEL_DIR JOB.gcode`: where the G-code firmware's sample
loop spends its cycles, on simavr (docs/motion.md, "The sample loop's cost").

The job runs on the simulated chip as `nnik job` runs it (the build options its file uses), with
the job harness's -p: the cycles of every instruction run while the busy pin is high, summed per
function (avr-nm's symbols) and per part of the loop, per planned sample. The stepper interrupts
that fall inside busy time are their own row, the call prologues (-mcall-prologues) another.
"""

from __future__ import annotations

import argparse
import bisect
import subprocess
import sys
import tempfile
from collections import Counter
from dataclasses import replace
from pathlib import Path

PARTS = {  # a part of the loop: the functions it runs (the IK: NAME_ik)
    "the planner's sample": ("nnik_pl_sample", "can_go", "mul_q30", "nnik_pl_ready", "acc_axis", "__mulsi3",
                             "__muluhisi3", "__umulhisi3"),
    # the shaper is inline in out_sample (nnik_shaper.h): one frame for both
    "the shaper and the step counts (out_sample)": ("out_sample", "nnik_sh_step", "__usmulhisi3",
                                                    "__usmulhisi3_tail"),
    "the segment queue": ("emit", "sample", "nnik_grbl_poll", "nnik_grbl_wait", "nnik_port_idle", "nnik_gc_ahead",
                          "commit", "nnik_port_room", "emit_wait", "fill"),
    "the stepper interrupt": ("__vector_11", "nnik_tick_slow", "__vectors"),
    "call prologues and epilogues": ("__prologue_saves__", "__epilogue_restores__"),
}


def symbols(elf: Path) -> tuple[list[int], list[str]]:
    from nnik.targets.toolchain import find_tool

    out = subprocess.run([find_tool("avr-nm"), "-n", "-C", str(elf)], capture_output=True, text=True, check=True).stdout
    rows = [(int(f[0], 16), f[2].split("(")[0]) for f in (ln.split(maxsplit=2) for ln in out.splitlines())
            if len(f) == 3 and f[1] in "tTwW"]
    return [a for a, _ in rows], [n for _, n in rows]


def by_function(profile: Path, elf: Path) -> Counter:
    addrs, names = symbols(elf)
    cyc = Counter()
    for line in profile.read_text().splitlines():
        pc, c = line.split()
        i = bisect.bisect_right(addrs, int(pc, 16)) - 1
        cyc[names[i] if i >= 0 else "?"] += int(c)
    return cyc


def by_part(cyc: Counter, ik: str) -> dict[str, int]:
    parts = {k: sum(cyc[f] for f in fs) for k, fs in PARTS.items()}
    parts["the IK"] = cyc[ik]
    parts["block planning, parsing, replies"] = sum(cyc.values()) - sum(parts.values())
    return parts


def profile_job(model: Path, job: Path, shaper: str, sample_hz: int, mcu: str, work: Path) -> dict:
    from nnik.bench.motion import ZVD
    from nnik.firmware.arduino import export_arduino
    from nnik.firmware.config import default_machine, shaper_taps
    from nnik.firmware.gcode import chip
    from nnik.firmware.gcode.job_input import JobOptions, prepare, read_job
    from nnik.firmware.gcode.motion import interpret, plan_steps
    from nnik.firmware.gcode.reader import sendable
    from nnik.firmware.ik_oracle import ik_oracle, load_scenario_of

    cfg = replace(default_machine(load_scenario_of(model), "none"), sample_hz=sample_hz, mcu=mcu)
    if shaper != "none":
        cfg = replace(cfg, shaper=shaper, shaper_taps=shaper_taps(shaper, ZVD, sample_hz))
    prep = prepare(read_job(job), cfg, JobOptions(), str(job))
    lines = [sendable(ln).decode("latin-1") for ln in prep.lines]
    cfg = prep.cfg
    lib = export_arduino(model, work / "lib", cfg)
    fw = chip.build_sketch(work / "lib", f"{lib['name']}_gcode", work / "build", chip.file_run_defines(cfg), mcu=mcu)
    seg = plan_steps(interpret(lines, cfg), cfg, ik_oracle(model))
    samples = int((seg.kind == 0).sum())
    (work / "lines.txt").write_text("".join(f"{ln}\n" for ln in lines), encoding="latin-1")
    exe = chip.build_harness(work / "build")
    secs = 2.0 + 1.5 * seg.ticks.sum() / cfg.tick_hz
    subprocess.run([str(exe), "-m", mcu, "-e", str(work / "events.bin"), "-p", str(work / "profile.txt"), str(fw.elf),
                    str(work / "lines.txt"), f"{secs:g}"], cwd=work, check=True, capture_output=True)
    cyc = by_function(work / "profile.txt", fw.elf)
    return {"samples": samples, "parts": by_part(cyc, f"{lib['name']}_ik"), "functions": cyc}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.sample_profile", description=__doc__.split("\n")[0])
    ap.add_argument("model", type=Path, help="model directory (nnik run's)")
    ap.add_argument("job", type=Path, help="G-code file")
    ap.add_argument("--shaper", default="zvd", help="none or a shaper kind, at 40 Hz, zeta 0.1 (default zvd)")
    ap.add_argument("--sample-hz", type=int, default=1000)
    ap.add_argument("--mcu", default="atmega328p")
    ap.add_argument("--functions", type=int, default=0, help="also the N busiest functions")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="nnik-profile-") as tmp:
        r = profile_job(args.model, args.job, args.shaper, args.sample_hz, args.mcu, Path(tmp))
    n = max(r["samples"], 1)
    print(f"{args.job.name}: {r['samples']} samples, busy cycles a sample {sum(r['parts'].values()) / n:,.0f}")
    for part, c in r["parts"].items():
        print(f"  {part:44s} {c / n:8,.0f}")
    for name, c in r["functions"].most_common(args.functions):
        print(f"    {name:34s} {c / n:8,.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
