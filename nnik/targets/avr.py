"""Run generated model C on an ATmega328P (16 MHz) under simavr.

Build: avr-gcc -mmcu=atmega328p <opt> (the model sources are compiled once, the
harness ``codegen/harness/avr/nnik_harness_avr.c`` once per batch of vectors).
Run:   simavr -m atmega328p -f 16000000 prog.elf; the harness prints one line per
vector over UART0 (simavr echoes UART lines on stderr, wrapped in colour codes;
the parser looks only for the harness's "@@" tokens).

Cycles: Timer1 at prescaler 1 around each call, minus the cost of an empty timed
region; calls longer than 65535 cycles are handled by counting Timer1 overflows
(the ISR's own cost is calibrated at start-up and subtracted).

Sizes: ``flash_bytes``/``ram_bytes`` are those of the whole harness program with a
one-vector table (text+data / data+bss from avr-size; RAM excludes the stack).
``model_*`` are the model's own bytes, read from the linker map of the smallest
program that calls it (codegen/harness/nnik_size_main.c; see nnik.targets.avr_sizes):
its code, PROGMEM tables and data and every libgcc/libm/libc routine it pulls in
(listed in ``model_runtime``).  ``stub_delta_*`` are the older figures (harness with
the model minus harness with a stub), which net out routines the harness also uses.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from .avr_sizes import model_sizes
from .toolchain import (HARNESS_DIR, TargetError, c_ident, find_tool, progress_bar, require,
                        run, split_batches, to_int32, tool_version, write_harness_inputs)

MCU = "atmega328p"
CLOCK_HZ = 16_000_000
DEFAULT_BATCH = 512

_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_HEX = r"[0-9a-f]{8}"


def _opt_tag(opt: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "", opt) or "default"


def compile_flags(opt: str, extra: Sequence[str] = ()) -> List[str]:
    return [f"-mmcu={MCU}", f"-DF_CPU={CLOCK_HZ}UL", opt, "-std=gnu99",
            "-ffunction-sections", "-fdata-sections", *extra]


def elf_sizes(elf: Path, wd: Path) -> Dict[str, int]:
    """An AVR ELF's flash (.text + .data) and RAM (.data + .bss + .noinit), bytes (avr-size -A)."""
    res = run([find_tool("avr-size"), "-A", elf], "avr-size", cwd=wd)
    sec: Dict[str, int] = {}
    for line in res.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[0].startswith(".") and parts[1].isdigit():
            sec[parts[0]] = int(parts[1])
    flash = sec.get(".text", 0) + sec.get(".data", 0)
    ram = sec.get(".data", 0) + sec.get(".bss", 0) + sec.get(".noinit", 0)
    return {"flash": flash, "ram": ram}


def parse_simavr_output(text: str, n: int, n_out: int):
    """Parse the harness's UART lines out of simavr's output.

    Returns (outputs (n, n_out), flags (n,), cycles (n,), calibration dict)."""
    clean = _ANSI.sub("", text)
    cal = re.search(rf"@@C ({_HEX}) ({_HEX})", clean)
    if not cal:
        raise TargetError("simavr: harness produced no calibration line (program did not start?)")
    if len(re.findall(rf"@@C {_HEX}", clean)) > 1:
        raise TargetError("simavr: the harness started twice (the chip reset during the batch)")
    if not re.search(rf"@@E {_HEX}", clean):
        raise TargetError("simavr: harness did not reach the end marker (crash or reset?)")
    pat = re.compile(r"@@V ({h})((?: {h}){{{k}}})".format(h=_HEX, k=n_out + 2))
    outputs = np.zeros((n, n_out), dtype=np.int64)
    flags = np.zeros(n, dtype=np.int64)
    cycles = np.zeros(n, dtype=np.int64)
    seen = np.zeros(n, dtype=bool)
    for m in pat.finditer(clean):
        i = int(m.group(1), 16)
        vals = [int(x, 16) for x in m.group(2).split()]
        if i >= n:
            raise TargetError(f"simavr: vector index {i} out of range")
        outputs[i] = [to_int32(v) for v in vals[:n_out]]
        flags[i] = to_int32(vals[n_out])
        cyc = vals[n_out + 1]
        if cyc & 0x80000000:
            raise TargetError(f"simavr: negative cycle count for vector {i} (timer calibration off)")
        cycles[i] = cyc
        seen[i] = True
    if not seen.all():
        raise TargetError(f"simavr: got results for {int(seen.sum())} of {n} vectors")
    return outputs, flags, cycles, {"empty": int(cal.group(1), 16), "isr": int(cal.group(2), 16)}


def run_avr(sources: Sequence[Path], include_dirs: Sequence[Path], name: str, vectors,
            opt: str = "-Os", workdir: Optional[Path] = None, n_out: int = 2,
            batch_size: int = DEFAULT_BATCH, extra_cflags: Sequence[str] = (),
            timeout: Optional[float] = None, progress: Optional[bool] = None) -> Dict:
    require("avr")
    name = c_ident(name)
    vec = np.asarray(vectors, dtype=np.int64)
    if vec.ndim != 2 or len(vec) == 0:
        raise TargetError(f"vectors must have shape (N, n_in), got {vec.shape}")
    n = len(vec)
    if workdir is None:
        import tempfile
        workdir = Path(tempfile.mkdtemp(prefix="nnik-avr-"))
    wd = Path(workdir) / f"avr-{_opt_tag(opt)}"
    wd.mkdir(parents=True, exist_ok=True)

    gcc = find_tool("avr-gcc")
    flags = compile_flags(opt, extra_cflags)
    incs = [f"-I{Path(d).resolve()}" for d in include_dirs]

    # model objects, compiled once
    objs: List[Path] = []
    for k, src in enumerate(sources):
        src = Path(src).resolve()
        if not src.is_file():
            raise TargetError(f"source not found: {src}")
        obj = wd / f"model{k}_{src.stem}.o"
        run([gcc, *flags, *incs, "-c", src, "-o", obj], f"avr-gcc {src.name}", cwd=wd,
            log=wd / f"{obj.stem}.log")
        objs.append(obj)

    harness = HARNESS_DIR / "avr" / "nnik_harness_avr.c"
    stub = HARNESS_DIR / "nnik_stub_model.c"

    def build(tag: str, vecs: np.ndarray, model_objs: List[Path]) -> Path:
        bdir = wd / tag
        write_harness_inputs(bdir, name, vecs, n_out)
        hobj = bdir / "harness.o"
        run([gcc, *flags, f"-I{bdir}", "-c", harness, "-o", hobj], "avr-gcc harness", cwd=bdir,
            log=bdir / "harness.log")
        elf = bdir / "prog.elf"
        run([gcc, f"-mmcu={MCU}", opt, "-Wl,--gc-sections", "-o", elf, hobj, *model_objs, "-lm"],
            "avr-gcc link", cwd=bdir, log=bdir / "link.log")
        return elf

    # sizes: one-vector programs with the model and with the stub
    n_in = vec.shape[1]
    stub_obj = wd / "stub.o"
    run([gcc, *flags, f"-DNNIK_IK={name}_ik", f"-DNNIK_N_IN={n_in}", f"-DNNIK_N_OUT={n_out}",
         "-c", stub, "-o", stub_obj], "avr-gcc stub", cwd=wd, log=wd / "stub.log")
    size_model = elf_sizes(build("size_model", vec[:1], objs), wd)
    size_stub = elf_sizes(build("size_stub", vec[:1], [stub_obj]), wd)

    def link_size_main(tag: str, call: int, model_objs: List[Path]) -> str:
        bdir = wd / tag
        bdir.mkdir(parents=True, exist_ok=True)
        mobj = bdir / "nnik_size_main.o"
        run([gcc, *flags, f"-DNNIK_IK={name}_ik", f"-DNNIK_N_IN={n_in}", f"-DNNIK_N_OUT={n_out}",
             f"-DNNIK_CALL={call}", "-c", HARNESS_DIR / "nnik_size_main.c", "-o", mobj], "avr-gcc size main",
            cwd=bdir, log=bdir / "main.log")
        mapf = bdir / "prog.map"
        run([gcc, f"-mmcu={MCU}", opt, "-Wl,--gc-sections", f"-Wl,-Map={mapf}", "-o", bdir / "prog.elf", mobj,
             *model_objs, "-lm"], "avr-gcc link", cwd=bdir, log=bdir / "link.log")
        return mapf.read_text(errors="replace")

    own = model_sizes(link_size_main("size_own", 1, objs), link_size_main("size_none", 0, []),
                      {str(o) for o in objs})

    simavr = find_tool("simavr")
    outputs = np.zeros((n, n_out), dtype=np.int64)
    rflags = np.zeros(n, dtype=np.int64)
    cycles = np.zeros(n, dtype=np.int64)
    cal = {}
    bar = progress_bar(n, f"simavr {name} {opt}", progress)
    try:
        for b, (s, e) in enumerate(split_batches(n, batch_size)):
            elf = build(f"batch{b}", vec[s:e], objs)
            t = timeout if timeout is not None else 120.0 + 0.5 * (e - s)
            res = run([simavr, "-m", MCU, "-f", str(CLOCK_HZ), elf], "simavr", cwd=elf.parent,
                      timeout=t, log=elf.parent / "simavr.log")
            o, f, c, cal = parse_simavr_output(res.stdout + "\n" + res.stderr, e - s, n_out)
            outputs[s:e], rflags[s:e], cycles[s:e] = o, f, c
            bar.update(e - s)
    finally:
        bar.close()

    cflags_str = " ".join(flags)
    return {
        "target": "avr",
        "mcu": MCU,
        "outputs": outputs,
        "flags": rflags,
        "cycles": cycles,
        "cycles_mean": float(cycles.mean()),
        "cycles_max": int(cycles.max()),
        "flash_bytes": size_model["flash"],
        "ram_bytes": size_model["ram"],
        "model_flash_bytes": own["flash"],
        "model_ram_bytes": own["ram"],
        "model_runtime": own["runtime"],
        "stub_delta_flash_bytes": size_model["flash"] - size_stub["flash"],
        "stub_delta_ram_bytes": size_model["ram"] - size_stub["ram"],
        "clock_hz": CLOCK_HZ,
        "cycle_hz": CLOCK_HZ,
        "us_mean": float(cycles.mean()) / CLOCK_HZ * 1e6,
        "compiler": tool_version("avr-gcc"),
        "compiler_flags": cflags_str,
        "simulator": "simavr",
        "calibration": cal,
        "workdir": str(wd),
    }
