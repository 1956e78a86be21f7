"""Static cost of the ``lut`` and ``hybrid`` families: the generated assembly, counted.

cycles = a + b * (cycles of the straight-line path through the assembly; the halves of the
input folds and output negations count half), flash = a + b * (bytes of the assembly) + table
bytes, each (a, b) fitted by least squares on simulator runs of reference configurations
(:mod:`nnik.implementations.lut.calibrate`) and stored in ``nnik/calibration/{family}.json``
with the hash of those configurations' emitted C. ``validated`` is true when that hash still
matches the C the generator emits today and the fit stayed within 3 % on the validation
configurations not used to fit it.
"""

from __future__ import annotations

import json
import re
from functools import lru_cache
from pathlib import Path

from nnik.implementations.cost_band import stated_band

CALIBRATION = Path(__file__).resolve().parents[2] / "calibration"
TOLERANCE = 0.03

# AVR: cycles and bytes per instruction (in-domain path); the nnik_kernel.h macros as a whole
AVR_CYC = {"lpm": 3, "mul": 2, "mulsu": 2, "movw": 1, "ld": 2, "st": 2, "adiw": 2, "sbiw": 2, "rjmp": 2}
AVR_MACRO = {"nnik_inw": (22, 56), "nnik_satge": (9, 20), "nnik_satlt": (9, 20)}
# PIC18: instruction cycles and bytes
P18_CYC = {"movff": 2, "tblrd*+": 2, "bra": 2}
P18_MACRO = {"NNIK_P18_INW": (27, 84), "NNIK_P18_SATGE": (12, 44), "NNIK_P18_SATLT": (12, 46)}


def _half_blocks(lines: list[str], is_branch, is_label) -> list[float]:
    """Weight per line: 0.5 inside a conditional block (from a forward branch to its label)."""
    w, inside = [], False
    for ln in lines:
        if inside and is_label(ln):
            inside = False
            w.append(0.0)
            continue
        w.append(0.5 if inside else 1.0)
        if is_branch(ln):
            inside = True
    return w


def avr_static(lines: list[str]) -> tuple[float, int]:
    """(cycles, bytes) of the AVR assembly lines of :func:`nnik.implementations.lut.avr.lines`."""
    w = _half_blocks(lines, lambda s: s.split()[0] in ("brpl", "rjmp"), lambda s: s.endswith(":"))
    cyc, nbytes = 0.0, 0
    for ln, wt in zip(lines, w):
        op = ln.split()[0]
        if ln.endswith(":"):
            continue
        c, b = AVR_MACRO.get(op, (AVR_CYC.get(op, 1), 2))
        cyc += wt * c
        nbytes += b
    from nnik.implementations.lut.avr import saved_registers

    n = saved_registers(lines)  # push + pop in gcc's prologue and epilogue
    return cyc + 4 * n, nbytes + 4 * n


def p18_static(items: list) -> tuple[float, int]:
    """(cycles, bytes) of the PIC18 items of :func:`nnik.implementations.lut.p18.items`."""
    lines = [s if kind == "asm" else "MACRO " + s for kind, s in items]
    w = _half_blocks(lines, lambda s: s.startswith("bra ") and "_L" in s, lambda s: s.endswith(":"))
    cyc, nbytes = 0.0, 0
    for ln, wt in zip(lines, w):
        if ln.endswith(":") or ln.startswith("BANKSEL"):
            nbytes += 0 if ln.endswith(":") else 2
            continue
        if ln.startswith("MACRO "):
            name = re.match(r"MACRO (\w+)", ln).group(1)
            c, b = P18_MACRO[name]
        else:
            op = ln.split()[0]
            c, b = P18_CYC.get(op, 1), 4 if op == "movff" else 2
        cyc += wt * c
        nbytes += b
    return cyc, nbytes


def static_counts(impl, target: str) -> tuple[float, int]:
    from nnik.implementations.lut.c import table_ctx

    ctx = table_ctx(impl.problem, impl.table)
    if target == "avr":
        return avr_static(impl.avr_lines(ctx))
    if target == "pic18":
        return p18_static(impl.p18_items(ctx))
    raise ValueError(f"unknown target {target!r}")


@lru_cache(maxsize=None)
def load(family: str) -> dict | None:
    p = CALIBRATION / f"{family}.json"
    if not p.exists():
        return None
    return json.loads(p.read_text())


@lru_cache(maxsize=None)
def calibration_current(cls) -> bool:
    """True if the stored calibration's key is the hash of today's reference C."""
    from nnik.implementations.lut.reference import reference_hash

    cal = load(cls.family)
    return cal is not None and cal.get("key") == reference_hash(cls)


def estimate(impl, target: str) -> dict:
    cyc, code = static_counts(impl, target)
    cal = load(impl.family)
    ram = 0 if target == "avr" else 47
    if cal is None or target not in cal["targets"]:
        return {"cycles": cyc, "flash_bytes": int(code + impl.model_bytes()), "ram_bytes": ram, "validated": False}
    c = cal["targets"][target]
    ok = bool(c["validated"]) and calibration_current(type(impl))
    return {"cycles": float(c["cycles"][0] + c["cycles"][1] * cyc),
            "flash_bytes": int(round(c["flash"][0] + c["flash"][1] * code)) + impl.model_bytes(),
            "ram_bytes": int(c.get("ram", ram)), "validated": ok,
            "cycles_error_pct": stated_band(cal, target)}
