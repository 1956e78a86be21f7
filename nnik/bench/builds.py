"""`python -m nnik.bench.builds OUTDIR...`: flash and RAM of the G-code firmware's builds for each
model directory's pick, on the Uno and the Mega: the sender's build (`nnik export --arduino`: the
Uno's default options, soft limits), a job's build with no options (what most files need), every
option on the Uno, and every option on the Mega. A build over the MCU's limit says by how much."""

from __future__ import annotations

import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from nnik.firmware.config import FEATURES, UNO_FEATURES, default_machine
from nnik.firmware.ik_oracle import load_scenario_of


def builds(outdir: Path) -> list[tuple[str, str]]:
    from nnik import pipeline
    from nnik.firmware.arduino import export_arduino
    from nnik.firmware.gcode import chip
    from nnik.targets.toolchain import TargetError

    pipeline.export(outdir)
    cfg = default_machine(load_scenario_of(outdir))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        lib = export_arduino(outdir, work / "lib", cfg)
        name = lib["name"]
        cases = [("Uno, sender build (wcs, planes, soft limits)", replace(cfg, features=UNO_FEATURES), "atmega328p", {}),
                 ("Uno, a job's build, no options", replace(cfg, features=frozenset()), "atmega328p", None),
                 ("Uno, every option", replace(cfg, features=FEATURES), "atmega328p", None),
                 ("Mega, every option", replace(cfg, features=FEATURES), "atmega2560", None)]
        cases += [(f"Uno, a job's build, {f} alone", replace(cfg, features=frozenset({f})), "atmega328p", None)
                  for f in sorted(FEATURES)]
        for label, c, mcu, extra in cases:
            defines = c.defines() if extra is not None else chip.file_run_defines(c)
            try:
                fw = chip.build_sketch(work / "lib", f"{name}_gcode", work / f"build_{len(rows)}", defines, mcu=mcu)
                rows.append((label, f"{fw.flash_bytes:,} / {fw.ram_bytes:,}"))
            except TargetError as exc:
                rows.append((label, f"does not fit ({str(exc)[:80]})"))
    return rows


def main(argv: list[str]) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m nnik.bench.builds", description=__doc__.split("\n")[0])
    ap.add_argument("outdirs", nargs="*", default=["build/galvo_cba2012"], metavar="OUTDIR",
                    help="trained model directories (default: build/galvo_cba2012)")
    for outdir in ap.parse_args(argv).outdirs:
        scn = load_scenario_of(Path(outdir))
        print(f"{scn.name}: flash / RAM (B) of the G-code firmware")
        rows = builds(Path(outdir))
        base = dict(rows).get("Uno, a job's build, no options", "")
        for label, value in rows:
            cost = ""
            if label.endswith(" alone") and "/" in value and "/" in base:
                cost = f"  (+{int(value.split(' / ')[0].replace(',', '')) - int(base.split(' / ')[0].replace(',', '')):,} B flash)"
            print(f"  {label:48s} {value}{cost}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
