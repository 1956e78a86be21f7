"""The model's own flash and RAM on the PIC18, read from gplink .map files.

Two programs are linked with codegen/harness/nnik_size_main.c: one that calls the model and one
that does not. The model's bytes are every byte of the first program that belongs to

  - the model's own object files (code, constant tables, data), or
  - a library module (libsdcc, libm18f) that only the model's program contains: runtime routines
    such as __mulint, __mullong or __gptrget4 count even when a harness would use them too;

located by the symbols gplink lists with their defining file. Sections shared by several files
(.code holds every module's tables) are split at symbol addresses; the shared scratch registers
(.registers, r0x..) count up to the highest one the model's files use; sections without symbols
(.cinit) count by how much the model's program grew them. Not counted: the C startup (crt0i), the
SFR definitions, the calling main() and the software stack.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Dict, List, Set, Tuple

SFR_START = 0xF80
STACK_ADDR = 0x500


@dataclass(frozen=True)
class Section:
    name: str
    kind: str  # code, romdata, udata, idata
    addr: int
    location: str  # program | data
    size: int


@dataclass(frozen=True)
class Symbol:
    name: str
    addr: int
    location: str
    file: str


def parse_detail(text: str) -> Tuple[List[Section], List[Symbol]]:
    """Sections and symbols (with their defining .asm file) of a gplink map."""
    sections: List[Section] = []
    symbols: List[Symbol] = []
    part = None
    for line in text.splitlines():
        if "Section Info" in line:
            part = "sections"
            continue
        if "Program Memory Usage" in line:
            part = None
            continue
        if "Symbols - Sorted by Name" in line:
            part = "symbols"
            continue
        if "Symbols - Sorted by Address" in line:
            break
        parts = line.split()
        if part == "sections" and len(parts) == 5 and parts[2].startswith("0x"):
            sections.append(Section(parts[0], parts[1], int(parts[2], 16), parts[3], int(parts[4], 16)))
        elif part == "symbols" and len(parts) == 5 and parts[1].startswith("0x"):
            symbols.append(Symbol(parts[0], int(parts[1], 16), parts[2], parts[4]))
    return sections, symbols


def _files(symbols: List[Symbol]) -> Set[str]:
    return {s.file for s in symbols}


def _owned(sec: Section, syms: List[Symbol], owners: Set[str]) -> int:
    """Bytes of a section that belong to the owner files, split at symbol addresses."""
    inside = sorted({(s.addr, s.file) for s in syms if sec.addr <= s.addr < sec.addr + sec.size
                     and s.location == sec.location})
    if not inside:
        return -1  # no symbol: the caller decides
    starts = sorted({a for a, _ in inside})
    total = 0
    for i, a in enumerate(starts):
        lo = sec.addr if i == 0 else a
        hi = starts[i + 1] if i + 1 < len(starts) else sec.addr + sec.size
        if any(f in owners for b, f in inside if b == a):
            total += hi - lo
    return total


def model_sizes(model_map: str, empty_map: str, model_files: Set[str]) -> Dict[str, object]:
    """{"flash": bytes, "ram": bytes, "files": the owner files} of the model, from the maps of the
    programs with and without the model call. `model_files` are the model's .asm names."""
    secs, syms = parse_detail(model_map)
    esecs, esyms = parse_detail(empty_map)
    runtime = sorted(_files(syms) - _files(esyms) - set(model_files) - {"extern"})
    runtime = [f for f in runtime if not f.startswith("nnik_size_main")]
    owners = set(model_files) | set(runtime)
    empty_size = {s.name: s.size for s in esecs}
    flash = ram = 0
    for sec in secs:
        if sec.location == "program":
            got = _owned(sec, syms, owners)
            flash += got if got >= 0 else max(0, sec.size - empty_size.get(sec.name, 0))
        elif sec.addr < SFR_START and not (sec.addr == STACK_ADDR and sec.name.startswith("ustat_")):
            if sec.name == ".registers":
                regs = [s.addr for s in syms if s.location == "data" and s.file in owners
                        and re.fullmatch(r"r0x[0-9A-Fa-f]+", s.name) and sec.addr <= s.addr < sec.addr + sec.size]
                ram += (max(regs) - sec.addr + 1) if regs else 0
                continue
            got = _owned(sec, syms, owners)
            ram += got if got >= 0 else max(0, sec.size - empty_size.get(sec.name, 0))
    return {"flash": flash, "ram": ram, "runtime": runtime}
