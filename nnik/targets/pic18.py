"""Run generated model C on a PIC18F452 (SDCC pic16 port) under gpsim.

Build: sdcc -mpic16 -p18f452 --use-non-free -c (model sources once, the harness
``codegen/harness/pic18/nnik_harness_pic18.c`` once per batch of vectors, plus the
core SFR definitions ``pic18f452_sfr.c``), linked by gplink with 18f452_g.lkr,
crt0i.o first, then libm18f.lib and libsdcc.lib.

Run: one gpsim session per batch (``gpsim -i -s prog.cod -c script.stc``, stdin
closed).  The script sets ``break e`` on the empty marker functions
nnik_mark_start / nnik_mark_end (addresses from the .map), and for every vector
runs to each marker, reads ``cycles`` and, at the end marker, the bytes of
nnik_out[] and nnik_flag with ``reg(ADDR)``.  A call's cycles are the difference
between the two markers minus that of an empty marker pair.  gpsim's cycles are
instruction cycles (Fosc/4): ``cycle_hz`` is 4 MHz for a 16 MHz clock.

Sizes (from the gplink map): flash = program addresses used (bytes; ROM words =
bytes/2); RAM = data sections below the SFR area, excluding the software stack
reserved by ``#pragma stack``.  Whole-program figures are for a one-vector
harness.  ``model_*`` are the model's own bytes, read from the map of the smallest
program that calls it (codegen/harness/nnik_size_main.c; see nnik.targets.pic18_sizes):
its code, tables and data and every libsdcc/libm18f routine it pulls in (listed in
``model_runtime``).  ``stub_delta_*`` are the older figures (harness with the model
minus harness with a stub), which net out routines the harness also uses.

The harness disables the watchdog in its configuration bits (gpsim runs it: an
11.5 M-cycle batch used to reset the chip), and every vector's end marker checks
the harness's vector index, so a reset of any kind is a TargetError, not results
shifted by a restart.

SDCC pic16 limits a model must respect: no ``long long``/``int64_t`` (a syntax
error), int is 16 bits.  ``>>`` on negative signed values is arithmetic.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .pic18_sizes import model_sizes
from .toolchain import (HARNESS_DIR, TargetError, c_ident, find_tool, pic16_runtime,
                        progress_bar, require, run, split_batches, to_int32, tool_version,
                        write_harness_inputs)

DEVICE = "18f452"
CLOCK_HZ = 16_000_000
CYCLE_HZ = CLOCK_HZ // 4
DEFAULT_BATCH = 256
STACK_ADDR, STACK_SIZE = 0x500, 0xFF  # must match the #pragma stack of the harness
SFR_START = 0xF80


def compile_flags(extra: Sequence[str] = ()) -> List[str]:
    return ["-mpic16", f"-p{DEVICE}", "--use-non-free", *extra]


def parse_map(text: str) -> Tuple[Dict[str, int], int, int]:
    """(symbol -> address, flash bytes, ram bytes) from a gplink .map file."""
    syms: Dict[str, int] = {}
    flash = None
    ram = 0
    in_sections = False
    for line in text.splitlines():
        if "Section Info" in line:
            in_sections = True
            continue
        if "Program Memory Usage" in line:
            in_sections = False
        parts = line.split()
        if in_sections and len(parts) == 5 and parts[3] == "data":
            name, _typ, addr, _loc, size = parts
            a, sz = int(addr, 16), int(size, 16)
            if a >= SFR_START:
                continue
            if a == STACK_ADDR and name.startswith("ustat_"):
                continue  # software stack
            ram += sz
        m = re.match(r"\s*(\d+) program addresses used", line)
        if m:
            flash = int(m.group(1))
        if len(parts) >= 4 and parts[1].startswith("0x") and parts[2] in ("program", "data") \
                and not in_sections:
            syms.setdefault(parts[0], int(parts[1], 16))
    if flash is None:
        raise TargetError("gplink map: no 'program addresses used' line")
    return syms, flash, ram


def make_script(syms: Dict[str, int], n: int, n_out: int) -> str:
    try:
        a_start, a_end, a_done = (syms[s] for s in ("_nnik_mark_start", "_nnik_mark_end", "_nnik_done"))
        a_out, a_flag, a_idx = syms["_nnik_out"], syms["_nnik_flag"], syms["_nnik_idx"]
    except KeyError as e:
        raise TargetError(f"gplink map lacks harness symbol {e}") from None
    lines = [f"break e 0x{a_start:x}", f"break e 0x{a_end:x}", f"break e 0x{a_done:x}",
             "run", "echo @@S -1", "cycles", "run", "echo @@E -1", "cycles"]
    reads = [f"reg(0x{a_out + k:x})" for k in range(4 * n_out)] + [f"reg(0x{a_flag:x})"]
    reads += [f"reg(0x{a_idx:x})", f"reg(0x{a_idx + 1:x})"]  # the harness's own vector index
    for i in range(n):
        lines += ["run", f"echo @@S {i}", "cycles", "run", f"echo @@E {i}", "cycles",
                  f"echo @@R {i}", *reads]
    lines += ["run", "echo @@D", "quit", ""]
    return "\n".join(lines)


_CYC = re.compile(r"^\s*(?:\*\*gpsim>\s*)?(\d+) = 0x[0-9A-Fa-f]+\s*$")
_REG = re.compile(r"\] = \$([0-9A-Fa-f]+) = 0b[01]+")
_TAG = re.compile(r"@@([SERD])(?: (-?\d+))?")


_RESET = re.compile(r"^\s*(?:Reset:\s*(?!POR_RESET)\w+|WDT expired.*|Reset on .*)$", re.MULTILINE)


def parse_gpsim_output(text: str, n: int, n_out: int):
    """Parse a harness gpsim session.  Returns outputs, flags, cycles, overhead.

    A reset after the program started (watchdog, stack over/underflow, ...) is a TargetError:
    the harness would restart and the markers would pair results with the wrong vectors."""
    m = _RESET.search(text)
    if m:
        before = [int(t) for t in re.findall(r"@@S (\d+)", text[:m.start()])]
        where = f"during vector {before[-1]}" if before else "before the first vector"
        raise TargetError(f"gpsim: the chip reset {where} ({m.group(0).strip()})")
    start: Dict[int, int] = {}
    end: Dict[int, int] = {}
    regs: Dict[int, List[int]] = {}
    pending = None  # ("S"|"E", idx) waiting for a cycles line
    cur_r = None
    done = False
    for line in text.splitlines():
        m = _TAG.search(line)
        if m:
            kind, idx = m.group(1), m.group(2)
            if kind == "D":
                done = True
                continue
            idx = int(idx)
            if kind in "SE":
                pending, cur_r = (kind, idx), None
            else:
                cur_r, pending = idx, None
                regs[idx] = []
            continue
        if pending is not None:
            mc = _CYC.match(line)
            if mc:
                (start if pending[0] == "S" else end)[pending[1]] = int(mc.group(1))
                pending = None
            continue
        if cur_r is not None:
            mr = _REG.search(line)
            if mr:
                regs[cur_r].append(int(mr.group(1), 16))
    if -1 not in start or -1 not in end:
        raise TargetError("gpsim: calibration markers not reached (program did not start?)")
    if not done:
        missing = [i for i in range(n) if i not in end]
        raise TargetError(f"gpsim: program did not finish (results for {n - len(missing)} of {n} vectors)")
    overhead = end[-1] - start[-1]
    outputs = np.zeros((n, n_out), dtype=np.int64)
    flags = np.zeros(n, dtype=np.int64)
    cycles = np.zeros(n, dtype=np.int64)
    nbytes = 4 * n_out + 3
    for i in range(n):
        if i not in start or i not in end or len(regs.get(i, [])) != nbytes:
            raise TargetError(f"gpsim: incomplete results for vector {i}")
        b = regs[i]
        if b[-2] | b[-1] << 8 != i:
            raise TargetError(f"gpsim: vector {i} ended with the harness at vector {b[-2] | b[-1] << 8} "
                              "(the chip restarted?)")
        for k in range(n_out):
            outputs[i, k] = to_int32(b[4 * k] | b[4 * k + 1] << 8 | b[4 * k + 2] << 16 | b[4 * k + 3] << 24)
        f = b[4 * n_out]
        flags[i] = f - 256 if f & 0x80 else f
        cycles[i] = end[i] - start[i] - overhead
    return outputs, flags, cycles, overhead


def run_pic18(sources: Sequence[Path], include_dirs: Sequence[Path], name: str, vectors,
              workdir: Optional[Path] = None, n_out: int = 2, batch_size: int = DEFAULT_BATCH,
              extra_cflags: Sequence[str] = (), timeout: Optional[float] = None,
              progress: Optional[bool] = None) -> Dict:
    require("pic18")
    name = c_ident(name)
    vec = np.asarray(vectors, dtype=np.int64)
    if vec.ndim != 2 or len(vec) == 0:
        raise TargetError(f"vectors must have shape (N, n_in), got {vec.shape}")
    n, n_in = vec.shape
    if workdir is None:
        import tempfile
        workdir = Path(tempfile.mkdtemp(prefix="nnik-pic18-"))
    wd = Path(workdir) / "pic18"
    wd.mkdir(parents=True, exist_ok=True)

    sdcc = find_tool("sdcc")
    gplink = find_tool("gplink")
    rt = pic16_runtime()
    flags = compile_flags(extra_cflags)
    incs = [f"-I{Path(d).resolve()}" for d in include_dirs]

    def cc(src: Path, obj: Path, extra: Sequence[str] = (), what: Optional[str] = None) -> Path:
        # Relative output name on purpose: gplink stores each object's .asm path in the
        # .cod file truncated to 63 characters, and gpsim crashes (segfault) when such a
        # truncated path happens to name a directory.  Relative names stay short.
        run([sdcc, *flags, *extra, "-c", src, "-o", obj.name], what or f"sdcc {src.name}",
            cwd=obj.parent, log=obj.with_suffix(".log"))
        if not obj.is_file():
            raise TargetError(f"sdcc produced no {obj.name}")
        return obj

    objs: List[Path] = []
    for k, src in enumerate(sources):
        src = Path(src).resolve()
        if not src.is_file():
            raise TargetError(f"source not found: {src}")
        objs.append(cc(src, wd / f"model{k}_{src.stem}.o", incs))
    sfr = cc(HARNESS_DIR / "pic18" / "pic18f452_sfr.c", wd / "pic18f452_sfr.o")
    stub = cc(HARNESS_DIR / "nnik_stub_model.c", wd / "nnik_stub_model.o",
              [f"-DNNIK_IK={name}_ik", f"-DNNIK_N_IN={n_in}", f"-DNNIK_N_OUT={n_out}"])
    harness_src = HARNESS_DIR / "pic18" / "nnik_harness_pic18.c"

    def build(tag: str, vecs: np.ndarray, model_objs: List[Path]):
        bdir = wd / tag
        write_harness_inputs(bdir, name, vecs, n_out)
        hobj = cc(harness_src, bdir / "harness.o", [f"-I{bdir}"], "sdcc harness")
        hexf = bdir / "prog.hex"
        run([gplink, "-q", "-m", "-w", "-s", rt["linker_script"], "-o", hexf, rt["crt0i"], hobj,
             *model_objs, sfr, rt["libm"], rt["libsdcc"]], "gplink", cwd=bdir,
            log=bdir / "link.log")
        mapf = bdir / "prog.map"
        if not mapf.is_file():
            raise TargetError("gplink wrote no .map file")
        syms, fl, ram = parse_map(mapf.read_text(errors="replace"))
        return bdir / "prog.cod", syms, fl, ram

    _, _, flash_m, ram_m = build("size_model", vec[:1], objs)
    _, _, flash_s, ram_s = build("size_stub", vec[:1], [stub])

    def link_size_main(tag: str, call: int, model_objs: List[Path]) -> str:
        bdir = wd / tag
        bdir.mkdir(parents=True, exist_ok=True)
        mobj = cc(HARNESS_DIR / "nnik_size_main.c", bdir / "nnik_size_main.o",
                  [f"-DNNIK_IK={name}_ik", f"-DNNIK_N_IN={n_in}", f"-DNNIK_N_OUT={n_out}", f"-DNNIK_CALL={call}"])
        hexf = bdir / "prog.hex"
        run([gplink, "-q", "-m", "-w", "-s", rt["linker_script"], "-o", hexf, rt["crt0i"], mobj,
             *model_objs, sfr, rt["libm"], rt["libsdcc"]], "gplink", cwd=bdir, log=bdir / "link.log")
        return (bdir / "prog.map").read_text(errors="replace")

    own = model_sizes(link_size_main("size_own", 1, objs), link_size_main("size_none", 0, []),
                      {o.with_suffix(".asm").name for o in objs})

    gpsim = find_tool("gpsim")
    outputs = np.zeros((n, n_out), dtype=np.int64)
    rflags = np.zeros(n, dtype=np.int64)
    cycles = np.zeros(n, dtype=np.int64)
    overhead = 0
    bar = progress_bar(n, f"gpsim {name}", progress)
    try:
        for b, (s, e) in enumerate(split_batches(n, batch_size)):
            cod, syms, _, _ = build(f"batch{b}", vec[s:e], objs)
            script = cod.parent / "run.stc"
            script.write_text(make_script(syms, e - s, n_out))
            t = timeout if timeout is not None else 120.0 + 0.5 * (e - s)
            res = run([gpsim, "-i", "-s", cod.name, "-c", script.name], "gpsim", cwd=cod.parent,
                      timeout=t, log=cod.parent / "gpsim.log")
            o, f, c, overhead = parse_gpsim_output(res.stdout + "\n" + res.stderr, e - s, n_out)
            outputs[s:e], rflags[s:e], cycles[s:e] = o, f, c
            bar.update(e - s)
    finally:
        bar.close()

    return {
        "target": "pic18",
        "mcu": "PIC18F452",
        "outputs": outputs,
        "flags": rflags,
        "cycles": cycles,
        "cycles_mean": float(cycles.mean()),
        "cycles_max": int(cycles.max()),
        "flash_bytes": flash_m,
        "ram_bytes": ram_m,
        "model_flash_bytes": own["flash"],
        "model_ram_bytes": own["ram"],
        "model_runtime": own["runtime"],
        "stub_delta_flash_bytes": flash_m - flash_s,
        "stub_delta_ram_bytes": ram_m - ram_s,
        "clock_hz": CLOCK_HZ,
        "cycle_hz": CYCLE_HZ,
        "us_mean": float(cycles.mean()) / CYCLE_HZ * 1e6,
        "compiler": tool_version("sdcc"),
        "compiler_flags": " ".join(flags),
        "simulator": "gpsim",
        "calibration": {"empty": overhead},
        "workdir": str(wd),
    }
