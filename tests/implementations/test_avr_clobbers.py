"""Every register the lut/hybrid AVR assembly writes is declared to gcc (clobber, operand, r0/r1).

An undeclared call-saved register keeps its garbage after the call: the caller's variable in
it changes behind gcc's back (a `movw r12, r0` with only r12 listed broke the G-code sketch's
feed in r12-r15 while the self-test's outputs stayed bit-exact)."""

from __future__ import annotations

import re

import pytest

from nnik.implementations import family
from nnik.implementations.lut.reference import REFERENCES, reference_impl

# instructions that do not write their first register operand
NO_WRITE = {"st", "std", "sts", "cp", "cpc", "cpi", "tst", "sbrs", "sbrc", "sbic", "sbis", "out", "push",
            "cpse", "rjmp", "rcall", "ret"}
PAIR = {"movw", "adiw", "sbiw"}  # rN names the pair rN+1:rN
MUL = {"mul", "muls", "mulsu", "fmul", "fmuls", "fmulsu"}  # write r1:r0
OPERAND_PAIRS = {"z": (30, 31), "x": (26, 27), "y": (28, 29)}


def written(asm_lines: list[str]) -> set[int]:
    """Registers an AVR instruction list may write (macros: every register argument)."""
    out = set()
    for ln in asm_lines:
        parts = ln.replace(",", " ").split()
        if not parts or ln.endswith(":") or parts[0].startswith(("br", ".")):
            continue
        op, regs = parts[0], [int(r) for r in re.findall(r"\br(\d+)\b", ln)]
        if op.startswith("nnik_"):
            out.update(regs)
        elif op in MUL:
            out.update((0, 1))
        elif op in PAIR:
            out.update((regs[0], regs[0] + 1))
        elif op == "lpm" and len(parts) == 1:
            out.add(0)
        elif op not in NO_WRITE and regs:
            out.add(regs[0])
    return out


def declared(src: str) -> tuple[list[str], set[int]]:
    """(asm lines, registers gcc is told about) of the AVR asm statement in generated C."""
    start = src.index("__asm__ __volatile__ (")
    stmt = src[start:src.index(");", start)]
    asm = [ln for ln in re.findall(r'"([^"]*?)\\n"', stmt)]
    clob = stmt[stmt.rindex(":"):]
    regs = {int(r) for r in re.findall(r'"r(\d+)"', clob)} | {0, 1}
    for letter, pair in OPERAND_PAIRS.items():
        if f'"+{letter}"' in stmt or f'"{letter}"' in stmt:
            regs.update(pair)
    regs.update(int(r) for r in re.findall(r'__asm__\("r(\d+)"\)', src[:start]))
    return asm, regs


def test_the_checker_sees_a_pair_half():
    assert written(["movw r12, r0"]) == {12, 13}
    assert written(["mul r3, r5", "st X+, r18"]) == {0, 1}


@pytest.mark.parametrize("fam,scenario,cfg", [(f, s, c) for f, refs in REFERENCES.items() for s, c, _ in refs])
def test_avr_asm_declares_every_register_it_writes(fam, scenario, cfg):
    im = reference_impl(family(fam), scenario, cfg)
    name = im.problem.name
    src = im.render_c()[f"{name}.c"]
    asm, regs = declared(src[src.index("NNIK_KERNEL_AVR"):])
    assert len(asm) > 20
    missing = written(asm) - regs
    assert not missing, f"undeclared registers {sorted(missing)}"
