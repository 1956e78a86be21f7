"""`make bench`: cycles, time, flash, RAM and accuracy per target, measured on the simulators.

Runs the shipped scenario end to end (or reuses its build directory), runs the MLP kernels and
the float math.h IK in the same harness on each simulated chip, adds the lut family's best as
the selection verified it (what a firmware engineer would write: a table), and prints one table
per target with seed 000's published Table 1 beside it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rich.console import Console
from rich.table import Table

from nnik import pipeline
from nnik.errors import NnikError
from nnik.machine.scenario import load_scenario

console = Console(highlight=False, width=None if sys.stdout.isatty() else 140)
# seed 000, Table 1: PIC18F452, CCS compiler, 16 MHz (4 MIPS): ROM words, time
PAPER_TABLE1 = [("paper: IK with math.h", 1977, 258.6e3), ("paper: MLP, math.h tanh", 2696, 38.0e3),
                ("paper: MLP, polynomial tanh", 3590, 7.2e3)]


def ensure_run(scenario: Path, outdir: Path | None) -> Path:
    scn = load_scenario(scenario)
    out = outdir or pipeline.default_outdir(scn)
    if not (out / pipeline.MODEL_FILE).is_file():
        pipeline.generate(scn, out)
        pipeline.train(scn, out)
        pipeline.evaluate(out)
    pipeline.verify(out, "host")
    for target in ("avr", "pic18"):
        pipeline.verify(out, target)
    if not pipeline.load_metrics(out).get("implementations"):
        try:
            pipeline.select(out)
        except NnikError as exc:  # no lut configuration meets max_error: its most accurate is still reported
            console.print(f"lut family: {exc}")
    return out


def target_table(m: dict, target: str) -> Table | str:
    t = m.get("targets", {}).get(target)
    if not t or "not_run" in t:
        return f"{target}: not run ({(t or {}).get('not_run', 'no target section in metrics.json')})"
    unit = "µstep" if m["unit"] == "microstep" else "LSB"
    clock = t["clock_hz"]
    title = f"{m['name']} on {target} ({t['compiler']}, {clock / 1e6:g} MHz): {t['points']} vectors, " \
            f"{t['mismatches']} mismatches vs the integer model"
    tab = Table(title=title)
    for c in ("implementation", "cycles", f"µs @ {clock / 1e6:g} MHz", "flash B", "RAM B", f"max error ({unit})",
              "speed-up vs float IK"):
        tab.add_column(c, justify="left" if c == "implementation" else "right")
    float_cycles = t["baselines"]["float"].get("cycles")
    cyc_per_us = clock / 1e6 / (4 if target == "pic18" else 1)

    def row(label, r):
        if "not_run" in r:
            tab.add_row(label, "not run", "", "", "", "", r["not_run"][:60])
            return
        err = f"{max(r['max_abs']):.3f}" if "max_abs" in r else "-"
        sp = f"{float_cycles / r['cycles']:.1f}x" if float_cycles else "-"
        tab.add_row(label, f"{r['cycles']:.0f}", f"{r['cycles'] / cyc_per_us:.1f}", str(r["flash_bytes"]),
                    str(r["ram_bytes"]), err, sp)

    for name, r in t["kernels"].items():
        row(f"MLP {m['network']['shape']}, kernel {name}", r)
    row("float math.h IK", t["baselines"]["float"])
    lut = next((r for r in m.get("implementations") or [] if r.get("family") == "lut"), None)
    if lut and isinstance((lut.get("targets") or {}).get(target), dict):
        row(f"lut family best: {lut['describe']}", {**lut["targets"][target], "max_abs": lut["delivered_max_abs"]})
    if target == "pic18":
        for label, words, us in PAPER_TABLE1:
            cyc = us * cyc_per_us
            tab.add_row(f"{label} (published, CCS)", f"{cyc:.0f}", f"{us:.0f}", f"{2 * words} ({words} words)", "-", "-", "-")
    return tab


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="nnik-bench", description=__doc__)
    ap.add_argument("scenario", nargs="?", default="datasets/galvo_cba2012.toml")
    ap.add_argument("-o", "--outdir", type=Path)
    args = ap.parse_args(argv)
    try:
        out = ensure_run(Path(args.scenario), args.outdir)
    except NnikError as exc:
        print(f"nnik bench: error: {exc}", file=sys.stderr)
        return 2
    m = pipeline.load_metrics(out)
    for target in ("avr", "pic18"):
        console.print(target_table(m, target))
    return 0


if __name__ == "__main__":
    sys.exit(main())
