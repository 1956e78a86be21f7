"""`python -m nnik.bench.plan_ram OUTDIR...`: the planner's lookahead against the Uno's SRAM.
For each model directory's pick, the Uno's sender build (`nnik export --arduino`) is built with
8, 12, 15 and 16 blocks, without a shaper and with ZVD at the scenario's [dynamics] resonance (40 Hz,
zeta 0.1 without one), at 1 kHz and 500 Hz; each build's static RAM (avr-size .data + .bss) and
flash, the stack's deepest point on simavr over the circle job, and what is left of the 2,048 B."""

from __future__ import annotations

import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from nnik.firmware.config import default_machine, shaper_taps
from nnik.firmware.ik_oracle import load_scenario_of

DEPTHS = (8, 12, 15, 16)
ZVD_DEFAULT = {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)}
JOB = Path(__file__).resolve().parents[2] / "datasets" / "jobs" / "circle.gcode"


def configs(scn):
    """(label, cfg) of the sender build: no shaper and ZVD, at 1 kHz and 500 Hz."""
    for hz in (1000, 500):
        base = replace(default_machine(scn, "none"), sample_hz=hz)
        yield f"none {hz} Hz", base
        taps = shaper_taps("zvd", getattr(scn, "dynamics", None) or ZVD_DEFAULT, hz)
        yield f"zvd {hz} Hz", replace(base, shaper="zvd", shaper_taps=taps)


def measure(outdir: Path, depths=DEPTHS) -> list[dict]:
    from nnik.firmware.arduino import export_arduino
    from nnik.firmware.gcode import chip
    from nnik.firmware.gcode.job_input import read_job
    from nnik.targets.toolchain import TargetError

    scn = load_scenario_of(outdir)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for label, cfg in configs(scn):
            for n in depths:
                c = replace(cfg, plan_blocks=n)
                lib = export_arduino(outdir, work / "lib", c)
                row = {"scenario": scn.name, "build": label, "blocks": n, "shaper_ram_bytes": c.shaper_ram_bytes}
                try:
                    fw = chip.build_sketch(work / "lib", f"{lib['name']}_gcode", work / "build", c.defines(),
                                           core_dir=work)
                except TargetError as exc:
                    rows.append({**row, "error": str(exc).splitlines()[0]})
                    continue
                res = chip.run_firmware(fw, [ln.decode("latin-1") for ln in read_job(JOB)], work / "build", 60.0)
                rows.append({**row, "flash_bytes": fw.flash_bytes, "ram_bytes": fw.ram_bytes,
                             "stack_bytes": res.stack_bytes, "left_bytes": chip.RAM_BYTES - fw.ram_bytes})
    return rows


def main(argv=None) -> int:
    dirs = [Path(a) for a in (sys.argv[1:] if argv is None else argv)]
    if not dirs:
        print("usage: python -m nnik.bench.plan_ram OUTDIR...", file=sys.stderr)
        return 2
    print("scenario            build          blocks  flash B  RAM B  stack B  left for the stack B (2,048 less RAM; >= 256)")
    for d in dirs:
        for r in measure(d):
            if "error" in r:
                print(f"{r['scenario']:<19} {r['build']:<14} {r['blocks']:>6}  {r['error']}")
                continue
            print(f"{r['scenario']:<19} {r['build']:<14} {r['blocks']:>6}  {r['flash_bytes']:>7,}  {r['ram_bytes']:>5,}"
                  f"  {r['stack_bytes']:>7}  {r['left_bytes']:>6}" + ("" if r["left_bytes"] >= 256 else "  < 256"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
