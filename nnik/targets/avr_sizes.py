"""The model's own flash and RAM on the AVR, read from GNU ld map files (-Wl,-Map).

As on the PIC18 (nnik.targets.pic18_sizes), two programs are linked with
codegen/harness/nnik_size_main.c, one calling the model and one not. The model's bytes are the
input sections the first program takes from

  - the model's object files (its code, PROGMEM tables, .data and .bss), or
  - an archive member (libgcc, libm, libc) that only the model's program contains: helpers such
    as __mulsi3 or __divmodsi4 count even when a harness would use them too;

flash is their .text and .data (the initial values live in flash), RAM their .data, .bss and
.noinit. Not counted: the vector table and C startup, the calling main() and alignment fill.
"""
from __future__ import annotations

import re
from typing import Dict, List, Set, Tuple

_OUT = re.compile(r"^(\.\S+)\s")  # an output section starts at column 0
_IN_FULL = re.compile(r"^ (\.\S+|COMMON)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")
_IN_NAME = re.compile(r"^ (\.\S+|COMMON)\s*$")
_IN_REST = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")

FLASH_SECTIONS = (".text", ".data")
RAM_SECTIONS = (".data", ".bss", ".noinit")


def parse_inputs(text: str) -> List[Tuple[str, int, str]]:
    """(output section, size, input file) of every input section of a GNU ld map."""
    out: List[Tuple[str, int, str]] = []
    body = text.split("Linker script and memory map", 1)[-1]
    current = None
    pending = False
    for line in body.splitlines():
        m = _OUT.match(line)
        if m:
            current, pending = m.group(1), False
            continue
        if current is None:
            continue
        m = _IN_FULL.match(line)
        if m:
            out.append((current, int(m.group(3), 16), m.group(4).strip()))
            pending = False
            continue
        if _IN_NAME.match(line):
            pending = True
            continue
        if pending:
            m = _IN_REST.match(line)
            if m:
                out.append((current, int(m.group(2), 16), m.group(3).strip()))
            pending = False
    return out


def _member(f: str) -> bool:
    return f.endswith(")") and ".a(" in f


def model_sizes(model_map: str, empty_map: str, model_objs: Set[str]) -> Dict[str, object]:
    """{"flash", "ram", "runtime"} of the model from the maps of the programs with and without
    the model call; `model_objs` are the model's object file paths as given to the linker."""
    inputs = parse_inputs(model_map)
    empty_files = {f for _, _, f in parse_inputs(empty_map)}
    runtime = sorted({f for _, _, f in inputs if _member(f) and f not in empty_files})
    owners = set(model_objs) | set(runtime)
    flash = sum(size for sec, size, f in inputs if sec in FLASH_SECTIONS and f in owners)
    ram = sum(size for sec, size, f in inputs if sec in RAM_SECTIONS and f in owners)
    short = [re.sub(r"^.*/", "", f) for f in runtime]
    return {"flash": flash, "ram": ram, "runtime": short}
