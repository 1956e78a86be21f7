"""The call graph between the firmware's C files, read from their objects, and its circles.

A file depends on another when its object leaves a symbol undefined (a function it calls, a
variable it uses) that the other's object defines (`nm`). The firmware's engine files
(codegen/arduino/src/*.c) must form no circle: no two files that reach each other, directly or
through others. The sketch (examples/NAME_gcode) is outside: it supplies the serial port that
nnik_grbl.c calls (nnik_port_*, declared in nnik_grbl.h) and calls nnik_grbl_run.

    python3 scripts/c_calls.py     # every engine file compiled with every build option; the graph; exit 1 on a circle

The files are compiled with the host's gcc at -O0 (no call inlined away, every branch of every
option kept) against a configuration header rendered for a shipped scenario's default machine
and an IK of the model API (no trained model needed).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SRC = ROOT / "codegen" / "arduino" / "src"
SCENARIO = ROOT / "datasets" / "galvo_cba2012.toml"
STUB = "nnik_stub"
# every build option and the code paths of the widest tool rule on (the sketch's build passes
# each as -D; nnik_gcode_config.h only fills in what is not given)
EVERY_OPTION = {"NNIK_GC_G5": "1", "NNIK_GC_G93": "1", "NNIK_GC_PLANES": "1", "NNIK_GC_WCS": "1",
                "NNIK_GC_FRAME": "1", "NNIK_GC_SOFT_LIMITS": "1", "NNIK_GC_MARLIN": "1",
                "NNIK_GRBL_SETTING_WRITE": "1", "NNIK_GRBL_HOLD_RAMP": "1", "NNIK_GRBL_PAUSE_RESUMES": "1"}
# (tool, rule) builds whose union is compiled: a laser by S, a pen by Z (its tool code out of line),
# a pen by E (inline)
TOOL_BUILDS = ((0, 0), (1, 1), (1, 2))
# src/ also holds the closed-loop XY table's C (the controllers nnik_ctl_*, the excitation player nnik_excite*, the servo
# runtime nnik_servo*), built and exported on their own (nnik.firmware.servo), not the G-code engine
CLOSED_LOOP = ("nnik_ctl", "nnik_servo", "nnik_excite")


def engine_files(src: Path = SRC, suffixes=(".c",)) -> list[Path]:
    """The G-code engine's files of src/ (the closed loop's left out)."""
    return sorted(p for p in src.iterdir() if p.suffix in suffixes and not p.name.startswith(CLOSED_LOOP))


def symbols(obj: Path, nm: str = "nm") -> tuple[set[str], set[str]]:
    """(defined, undefined) global symbols of an object file."""
    out = subprocess.run([nm, "-g", str(obj)], capture_output=True, text=True, check=True).stdout
    defined, undefined = set(), set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0] == "U":
            undefined.add(parts[1])
        elif len(parts) == 3:
            defined.add(parts[2])
    return defined, undefined


def call_graph(objects: dict[str, list[Path]], nm: str = "nm") -> dict[str, set[str]]:
    """{file: the files whose symbols it uses}, from each file's objects (one per build)."""
    defined_by: dict[str, str] = {}
    uses: dict[str, set[str]] = {}
    for name, objs in objects.items():
        uses[name] = set()
        for obj in objs:
            d, u = symbols(obj, nm)
            uses[name] |= u
            for s in d:
                defined_by.setdefault(s, name)
    return {name: {defined_by[s] for s in u if s in defined_by and defined_by[s] != name}
            for name, u in uses.items()}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The graph's strongly connected parts of two files or more (each a circle), sorted (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = []
            while True:
                w = stack.pop()
                part.append(w)
                if w == v:
                    break
            if len(part) > 1:
                found.append(sorted(part))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return sorted(found)


def config_headers(workdir: Path) -> None:
    """nnik_gcode_config.h and nnik_grbl_config.h for the scenario's default machine, and an IK
    header of the model API, in workdir."""
    from nnik.firmware.arduino import _env
    from nnik.firmware.config import default_machine
    from nnik.machine.scenario import load_scenario

    cfg = default_machine(load_scenario(SCENARIO))
    env = _env()
    (workdir / "nnik_gcode_config.h").write_text(env.get_template("gcode_config.h.j2").render(
        name=STUB, origin=list(cfg.origin_um), seg_um=cfg.seg_um, tick_hz=cfg.tick_hz, feed_um_min=cfg.feed_um_min,
        tool=cfg.tool, shaper=cfg.shaper, tool_defines=cfg.defines()))
    (workdir / "nnik_grbl_config.h").write_text(env.get_template("grbl_config.h.j2").render(name=STUB, grbl_settings='""'))
    (workdir / f"{STUB}.h").write_text(f"#include <stdint.h>\nint8_t {STUB}_ik(const int32_t in_um[2], int32_t out[2]);\n")


def compile_engine(workdir: Path, cc: str = "gcc", src: Path = SRC) -> dict[str, list[Path]]:
    """{file name: its objects}: every src/*.c, once per tool build, with every option on."""
    from nnik.emit.templating import RUNTIME

    config_headers(workdir)
    objects: dict[str, list[Path]] = {}
    for c in engine_files(src):
        objects[c.name] = []
        for tool, rule in TOOL_BUILDS:
            obj = workdir / f"{c.stem}-{tool}{rule}.o"
            defines = {**EVERY_OPTION, "NNIK_GC_TOOL": str(tool), "NNIK_GC_RULE": str(rule)}
            r = subprocess.run([cc, "-std=c99", "-O0", "-c", f"-I{workdir}", f"-I{src}", f"-I{RUNTIME}",
                                *(f"-D{k}={v}" for k, v in defines.items()), str(c), "-o", str(obj)],
                               capture_output=True, text=True)
            if r.returncode != 0:
                raise RuntimeError(f"{c.name} does not compile: {r.stderr.strip()[:400]}")
            objects[c.name].append(obj)
    return objects


def engine_graph(cc: str = "gcc", nm: str = "nm") -> dict[str, set[str]]:
    with tempfile.TemporaryDirectory(prefix="nnik_c_calls_") as tmp:
        return call_graph(compile_engine(Path(tmp), cc), nm)


def main() -> int:
    if shutil.which("gcc") is None or shutil.which("nm") is None:
        print("c_calls: gcc and nm are needed", file=sys.stderr)
        return 2
    graph = engine_graph()
    for name in sorted(graph):
        print(f"{name}: {', '.join(sorted(graph[name])) or '-'}")
    found = circles(graph)
    for part in found:
        print(f"c_calls: a circle between {', '.join(part)}", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
