"""Build the library's sketches with Debian's Arduino AVR core and run them on simavr.

Build: avr-gcc/avr-g++ straight over the core's sources (arduino-core-avr, the IDE's flags; the
Uno's ATmega328P at 16 MHz by default, or the Mega's ATmega2560: MCUS), the sketch and the
library's src/, the compiles two at a time. Run: the harness
codegen/harness/arduino/nnik_simavr_job.c (linked against libsimavr) sends a job over UART0
and records every STEP/DIR edge, the segment marker and the busy pin with cycle times. After
the job's last line it sends M400 and waits for the answer, so every queued segment runs however
the job ends; the motion pin (D7, high while the stepper has a segment) tells when it fell idle.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nnik.firmware.gcode.simrun import ChipRun  # noqa: F401  (chip.ChipRun, as before)
from nnik.targets.avr import elf_sizes
from nnik.targets.toolchain import HARNESS_DIR, TargetError, find_tool, run

CORE_ROOT = Path(os.environ.get("NNIK_ARDUINO_AVR", "/usr/share/arduino/hardware/arduino/avr"))
SIMAVR_HEADER = Path("/usr/include/simavr/sim_avr.h")
HARNESS_SRC = HARNESS_DIR / "arduino" / "nnik_simavr_job.c"
CLOCK_HZ = 16_000_000


@dataclass(frozen=True)
class Mcu:
    """A board's chip: the Arduino core's variant and board macro, what a sketch may use."""

    name: str  # avr-gcc's -mmcu and simavr's core
    variant: str  # the Arduino core's variants/<variant>/pins_arduino.h
    board: str  # the IDE's -DARDUINO_AVR_<board>
    flash_bytes: int  # program flash less the bootloader
    ram_bytes: int


MCUS = {
    "atmega328p": Mcu("atmega328p", "standard", "ARDUINO_AVR_UNO", 32 * 1024 - 512, 2048),  # optiboot: 512 B
    "atmega2560": Mcu("atmega2560", "mega", "ARDUINO_AVR_MEGA2560", 256 * 1024 - 8192, 8192),  # stk500v2: 8 KiB
}
MCU = "atmega328p"
FLASH_BYTES = MCUS[MCU].flash_bytes
RAM_BYTES = MCUS[MCU].ram_bytes
C_FLAGS = ["-std=gnu11"]
# the code's size, and no cycle lost (measured with ZVD at 1 kHz on the shipped jobs: the sample
# loop's cycles fall too): -mrelax (the linker makes each call or jump within reach rcall/rjmp, 2 B
# and a cycle less), -mstrict-X (X not used as a base pointer with offsets), no moves of loop
# invariants and no tree loop passes (registers kept free in the loops); about 700 B of the Uno's
# G-code build
SIZE_FLAGS = ["-mrelax", "-mstrict-X", "-fno-move-loop-invariants", "-fno-tree-loop-optimize"]
# the G-code build's translation units whose functions run every sample, compiled without
# -mcall-prologues: each saves its registers with its own pushes and pops rather than through
# libgcc's __prologue_saves__/__epilogue_restores__ (fewer registers saved, no jump in and out, no
# frame set up through Y when the function has none), at some flash (the pushes in each function);
# with sample() inline at its loops (nnik_gc_segments.c), measured with ZVD at 1 kHz on the circle:
# 4,937 -> 4,781 busy cycles a sample on galvo, 5,042 -> 4,889 on CoreXY, for 320 B of flash;
# nnik_gc_segments.c too measured 4,889 -> 4,872 on CoreXY for +214 B (the docs' star build) and
# +240 B (the circle's): left out, slicer_xy's CoreXY build (32,114 B) would no longer fit the Uno
HOT_SOURCES = ("nnik_plan_sample.c",)
HOT_FLAGS = ["-mno-call-prologues"]
# Debian's avr-gcc 5.4 <float.h> defines DECIMAL_DIG for C only; WString.cpp needs it in C++
CXX_FLAGS = ["-std=gnu++11", "-fpermissive", "-fno-exceptions", "-fno-threadsafe-statics",
             "-DDECIMAL_DIG=__DECIMAL_DIG__"]


def mcu_of(name: str) -> Mcu:
    if name not in MCUS:
        raise TargetError(f"unknown MCU {name!r}; known: {', '.join(MCUS)}")
    return MCUS[name]


def common_flags(mcu: str = MCU) -> list[str]:
    m = mcu_of(mcu)
    return [f"-mmcu={m.name}", f"-DF_CPU={CLOCK_HZ}L", "-DARDUINO=10807", f"-D{m.board}", "-DARDUINO_ARCH_AVR",
            "-Os", "-g0", "-ffunction-sections", "-fdata-sections", "-mcall-prologues", *SIZE_FLAGS, "-Wall"]


COMMON = common_flags(MCU)


def file_run_defines(cfg) -> dict[str, str]:
    """The build of a file run (`nnik job`, the model-equality tests): the planner never flushes on a
    quiet line (NNIK_GRBL_QUIET_MS 0; the harness ends every job with M400), so the motion depends
    on the lines alone, as the model's does. A sender's build keeps grbl_config.h's 5 ms."""
    return {**cfg.defines(), "NNIK_GRBL_QUIET_MS": "0", "NNIK_GRBL_PAUSE_RESUMES": "1"}


def available() -> tuple[bool, str]:
    """(True, "") if avr-gcc, avr-g++, simavr, the Arduino core and libsimavr's headers are there."""
    missing = [t for t in ("avr-gcc", "avr-g++", "avr-size", "simavr", "gcc") if find_tool(t) is None]
    if not (CORE_ROOT / "cores" / "arduino" / "Arduino.h").is_file():
        missing.append(f"Arduino AVR core ({CORE_ROOT}, Debian package arduino-core-avr)")
    if not SIMAVR_HEADER.is_file():
        missing.append("libsimavr headers (Debian package libsimavr-dev)")
    if missing:
        return False, f"missing {', '.join(missing)}; run scripts/install_toolchains.sh"
    return True, ""


def _require() -> None:
    ok, why = available()
    if not ok:
        raise TargetError(why)


def _includes(mcu: str = MCU) -> list[str]:
    return [f"-I{CORE_ROOT / 'cores' / 'arduino'}", f"-I{CORE_ROOT / 'variants' / mcu_of(mcu).variant}"]


def _compile(src: Path, obj: Path, extra: list[str], cwd: Path, mcu: str = MCU) -> Path:
    if src.suffix in (".cpp", ".ino"):
        cmd = [find_tool("avr-g++"), *common_flags(mcu), *CXX_FLAGS, "-x", "c++"]
    elif src.suffix == ".S":
        cmd = [find_tool("avr-gcc"), *common_flags(mcu), "-x", "assembler-with-cpp"]
    else:
        cmd = [find_tool("avr-gcc"), *common_flags(mcu), *C_FLAGS]
    run([*cmd, *_includes(mcu), *extra, "-c", src, "-o", obj], f"compile {src.name}", cwd=cwd, log=obj.with_suffix(".log"))
    return obj


def _compile_all(jobs: list[tuple], cwd: Path, mcu: str) -> list[Path]:
    """_compile over (src, obj, extra) on every core (the compiles are independent processes)."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1)) as ex:
        return list(ex.map(lambda j: _compile(j[0], j[1], j[2], cwd, mcu), jobs))


def _absolute(*paths) -> list[Path]:
    """The paths made absolute against the caller's cwd: the tools below run with cwd= a build
    folder, so a relative -o, input or library path would point inside that folder."""
    return [Path(p).resolve() for p in paths]


def build_core(workdir: Path, mcu: str = MCU) -> Path:
    """core.a of the Arduino AVR core for the MCU's board (cached in workdir/core-MCU, keyed by
    the compiler's flags: a cache built with other flags is rebuilt)."""
    _require()
    core = CORE_ROOT / "cores" / "arduino"
    (workdir,) = _absolute(workdir)
    out = workdir / f"core-{mcu}"
    lib = out / "core.a"
    key = hashlib.sha256(" ".join([*common_flags(mcu), *CXX_FLAGS, *C_FLAGS, *_includes(mcu)]).encode()).hexdigest()
    stamp = out / "flags.sha256"
    if lib.is_file() and stamp.is_file() and stamp.read_text() == key:
        return lib
    out.mkdir(parents=True, exist_ok=True)
    srcs = sorted(p for p in core.iterdir() if p.suffix in (".c", ".cpp", ".S"))
    objs = _compile_all([(s, out / f"{s.name}.o", []) for s in srcs], out, mcu)
    tmp = out / "core.a.tmp"
    tmp.unlink(missing_ok=True)
    run([find_tool("avr-ar") or "avr-ar", "rcs", tmp, *objs], "avr-ar core", cwd=out)
    tmp.rename(lib)
    stamp.write_text(key)
    return lib


@dataclass
class Firmware:
    elf: Path
    flash_bytes: int
    ram_bytes: int
    mcu: str = MCU


def build_sketch(libdir: Path, example: str, workdir: Path, defines: dict | None = None, mcu: str = MCU,
                 core_dir: Path | None = None) -> Firmware:
    """Compile examples/EXAMPLE/EXAMPLE.ino with the library's src/ and the core for the MCU's
    board; link; size (flash: .text + .data; RAM: .data + .bss), checked against the MCU's
    limits. defines: macros for the sketch and src/ (the tool's, MachineConfig.defines());
    core_dir: where the core is cached (default workdir: one build for sketches that share it)."""
    libdir, workdir = _absolute(libdir, workdir)
    m = mcu_of(mcu)
    core = build_core(core_dir if core_dir is not None else workdir, mcu)
    sketch = libdir / "examples" / example / f"{example}.ino"
    bdir = workdir / (example if mcu == MCU else f"{example}-{mcu}")
    bdir.mkdir(parents=True, exist_ok=True)
    inc = [f"-I{libdir / 'src'}", *(f"-D{k}={v}" for k, v in (defines or {}).items())]
    gcode = example.endswith("_gcode")  # the sketch's emit and the stepper's queue run every sample too
    jobs = [(sketch, bdir / f"{example}.ino.o", [*inc, *(HOT_FLAGS if gcode else [])])]
    jobs += [(src, bdir / f"{src.name}.o", [*inc, *(HOT_FLAGS if src.name in HOT_SOURCES else [])])
             for src in sorted((libdir / "src").glob("*.c"))]
    objs = _compile_all(jobs, bdir, mcu)
    elf = bdir / f"{example}.elf"
    try:
        run([find_tool("avr-gcc"), f"-mmcu={m.name}", "-Os", *SIZE_FLAGS, "-Wl,--gc-sections", "-o", elf, *objs, core, "-lm"],
            f"link {example}", cwd=bdir, log=bdir / "link.log")
    except TargetError:
        over = re.search(r"region .text' overflowed by (\d+) bytes", (bdir / "link.log").read_text(errors="replace"))
        if over is None:
            raise
        raise TargetError(f"{example} does not fit the {mcu}: flash over by {over.group(1)} B beyond the linker's "
                          f"{m.flash_bytes // 1024 + 1} KiB region (the limit is {m.flash_bytes} B)") from None
    size = elf_sizes(elf, bdir)
    fw = Firmware(elf, size["flash"], size["ram"], mcu)
    if fw.flash_bytes > m.flash_bytes or fw.ram_bytes > m.ram_bytes:
        raise TargetError(f"{example} does not fit the {mcu}: flash {fw.flash_bytes} of {m.flash_bytes} B, "
                          f"RAM {fw.ram_bytes} of {m.ram_bytes} B")
    return fw


def _build_host_tool(src: Path, workdir: Path, libs: list[str], what: str) -> Path:
    """A simavr runner compiled for the host against libsimavr (cached by source hash)."""
    _require()
    (workdir,) = _absolute(workdir)
    h = hashlib.sha256(src.read_bytes())
    for header in sorted(src.parent.glob("*.h")):  # the runners share nnik_simavr_wire.h
        h.update(header.read_bytes())
    exe = workdir / f"{src.stem}-{h.hexdigest()[:12]}"
    if not exe.is_file():
        workdir.mkdir(parents=True, exist_ok=True)
        tmp = exe.with_suffix(".tmp")
        run([find_tool("gcc"), "-O2", "-Wall", "-Wextra", "-Werror", src, "-o", tmp, *libs], what, cwd=workdir)
        tmp.rename(exe)
    return exe


def build_harness(workdir: Path) -> Path:
    """The simavr job runner."""
    return _build_host_tool(HARNESS_SRC, workdir, ["-lsimavr"], "build the simavr harness")


PTY_HARNESS_SRC = HARNESS_DIR / "arduino" / "nnik_simavr_pty.c"


def build_pty_harness(workdir: Path) -> Path:
    """The simavr runner that puts the chip's UART on a pseudo-terminal (for real senders;
    nnik.firmware.gcode.pty_chip runs it)."""
    return _build_host_tool(PTY_HARNESS_SRC, workdir, ["-lsimavr", "-lutil"], "build the simavr pty harness")


def parse_events(text: str) -> ChipRun:
    replies, steps, marks, busy_edges, tool = [], [], [], [], []
    end_cycle, state, idle_cycle = 0, "missing", 0
    for line in text.splitlines():
        tag, _, rest = line.partition(" ")
        if tag == "R":
            cyc, _, msg = rest.partition(" ")
            replies.append((int(cyc), msg))
        elif tag == "S":
            c, m, d = rest.split()
            steps.append((int(c), int(m), int(d)))
        elif tag == "M":
            marks.append(int(rest))
        elif tag == "B":
            c, v = rest.split()
            busy_edges.append((int(c), int(v)))
        elif tag == "T":
            c, v = rest.split()
            tool.append((int(c), int(v)))
        elif tag == "D":
            idle_cycle = int(rest.partition(" ")[0])
        elif tag == "E":
            parts = rest.split()
            end_cycle, state = int(parts[0]), parts[1]
    rises = [c for c, v in busy_edges if v == 1]
    falls = [c for c, v in busy_edges if v == 0]
    n = min(len(rises), len(falls))
    return ChipRun(replies, np.asarray(steps, dtype=np.int64).reshape(-1, 3), np.asarray(marks, dtype=np.int64),
                   np.stack([rises[:n], falls[:n]], 1).astype(np.int64) if n else np.zeros((0, 2), np.int64),
                   end_cycle, state, idle_cycle, np.asarray(tool, dtype=np.int64).reshape(-1, 2))


GRBL_HEADER = HARNESS_DIR.parent / "arduino" / "src" / "nnik_grbl.h"
PROTOCOLS = ("counting", "send-response")  # grbl's streaming protocols (its wiki, "Interfacing with Grbl")


def rx_buffer_bytes() -> int:
    """The firmware's receive buffer (NNIK_GRBL_RX_SIZE in nnik_grbl.h): a character-counting
    sender keeps at most this many bytes of unanswered lines in flight."""
    m = re.search(r"^#define NNIK_GRBL_RX_SIZE (\d+)\b", GRBL_HEADER.read_text(), re.M)
    if m is None:
        raise TargetError(f"{GRBL_HEADER}: no NNIK_GRBL_RX_SIZE")
    return int(m.group(1))


def protocol_bytes(protocol: str) -> int:
    """The harness's budget for a streaming protocol: counting -> the receive buffer's bytes,
    send-response -> 0 (one line in flight)."""
    if protocol not in PROTOCOLS:
        raise TargetError(f"unknown streaming protocol {protocol!r}; known: {', '.join(PROTOCOLS)}")
    return rx_buffer_bytes() if protocol == "counting" else 0


def sent_lines(lines: list[str], protocol: str, clean: bool = True) -> list[str]:
    """The lines as the protocol's sender sends them: character counting's with whitespace and
    comments out where the reader reads the same (simrun.sender_line; clean False: as they are),
    send-response's as they are (grbl's simple_stream.py)."""
    from nnik.firmware.gcode.simrun import sender_line

    protocol_bytes(protocol)
    return [sender_line(ln) for ln in lines] if protocol == "counting" and clean else list(lines)


def run_firmware(fw: Firmware, lines: list[str], workdir: Path, max_seconds: float, mcu: str | None = None,
                 progress=None, protocol: str = "send-response", clean: bool = True) -> ChipRun:
    """Send lines to the firmware on simavr, then M400; the run ends when that is answered (all
    the motion done; state "done"), the firmware halts, crashes or max_seconds pass. mcu: the
    simulated chip (default the one fw was built for); progress(answers so far, the answer's cycle)
    after each answer; protocol: how the lines stream (PROTOCOLS: character counting within the
    firmware's receive buffer, or send-response, one line in flight); clean: sent_lines's."""
    from nnik.firmware.gcode.simrun import run_harness

    workdir, elf = _absolute(workdir, fw.elf)
    mcu_of(mcu or fw.mcu)
    return run_harness(build_harness(workdir), elf, sent_lines(lines, protocol, clean), workdir, max_seconds,
                       mcu or fw.mcu, progress, protocol_bytes(protocol))


def tool_missing_reason() -> str | None:
    ok, why = available()
    return None if ok else why


def clean(workdir: Path) -> None:
    shutil.rmtree(workdir, ignore_errors=True)
