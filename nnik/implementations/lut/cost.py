"""Static cost of the ``lut`` and ``hybrid`` families: the generated assembly, counted.

cycles = a + b * (cycles of the straight-line path through the assembly; the blocks behind a
sign test count half -- on PIC18, the lut's count each by the fraction of typical inputs that
take it: :func:`p18_taken`), flash = a + b * (bytes of the assembly) + table
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

import numpy as np

from nnik.implementations.cost_band import stated_band

CALIBRATION = Path(__file__).resolve().parents[2] / "calibration"
TOLERANCE = 0.03

# AVR: cycles and bytes per instruction (in-domain path); the nnik_kernel.h macros as a whole
AVR_CYC = {"lpm": 3, "mul": 2, "mulsu": 2, "movw": 1, "ld": 2, "st": 2, "adiw": 2, "sbiw": 2, "rjmp": 2}
AVR_MACRO = {"nnik_inw": (22, 56), "nnik_satge": (9, 20), "nnik_satlt": (9, 20)}
# PIC18: instruction cycles and bytes
P18_CYC = {"movff": 2, "tblrd*+": 2, "bra": 2}
P18_MACRO = {"NNIK_P18_INW": (27, 84), "NNIK_P18_SATGE": (12, 44), "NNIK_P18_SATLT": (12, 46)}


def _half_blocks(lines: list[str], is_branch, is_label, taken: list[float] | None = None) -> list[float]:
    """Weight per line: inside a conditional block (from a forward branch to its label) the
    fraction of calls that run it, taken[k] for the k-th block (default 0.5)."""
    w, inside, k, p = [], False, 0, 0.5
    for ln in lines:
        if inside and is_label(ln):
            inside = False
            w.append(0.0)
            continue
        w.append(p if inside else 1.0)
        if is_branch(ln):
            inside = True
            p = taken[k] if taken is not None and k < len(taken) else 0.5
            k += 1
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


def p18_static(items: list, taken: list[float] | None = None) -> tuple[float, int]:
    """(cycles, bytes) of the PIC18 items of :func:`nnik.implementations.lut.p18.items`
    (taken: the fraction of calls that run each conditional block, in order; default half).
    With taken, each test is priced as the chip runs it: a block that runs skips the branch
    over it (btfss: 2 cycles, no bra), one that does not runs the bra (2)."""
    lines = [s if kind == "asm" else "MACRO " + s for kind, s in items]
    is_branch = lambda s: s.startswith("bra ") and "_L" in s  # noqa: E731
    w = _half_blocks(lines, is_branch, lambda s: s.endswith(":"), taken)
    cyc, nbytes, k = 0.0, 0, 0
    for ln, wt in zip(lines, w):
        if taken is not None and is_branch(ln):
            p = taken[k] if k < len(taken) else 0.5
            k += 1
            cyc += p * 1 + (1 - p) * P18_CYC["bra"]  # the skip's second cycle, or the branch
            nbytes += 2
            continue
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
        items = impl.p18_items(ctx)
        return p18_static(items, p18_taken(impl, items) if impl.family == "lut" else None)
    raise ValueError(f"unknown target {target!r}")


def typical_cells(impl, n: int = 2000, seed: int = 12345):
    """Typical inputs (uniform in the domain, clamped): (ix, iy, neg (N, 2)) of the table."""
    p = impl.problem
    rng = np.random.default_rng(seed)
    c, _ = p.clamp(np.stack([rng.integers(p.lo[j], p.hi[j] + 1, n) for j in range(2)], 1))
    t, neg = impl.table.grid.t(c)
    (ix, iy), _ = impl.table.grid.index(t)
    return ix, iy, neg


def p18_taken(impl, items: list) -> list[float] | None:
    """The fraction of typical inputs that run each conditional block of the lut's PIC18 body,
    in order: a folded input's negation (x < 0), a multiply-accumulate's sign correction (the
    16-bit table difference < 0: e10 - e00, e01 - e00, e11 - e01 in that order,
    nnik.implementations.lut.p18.output_acc), an odd output's negation.  A monotone table never
    takes the correction: at half, a corexy table was priced 2.8 % high on gpsim.  None when
    the blocks are not the ones expected."""
    from nnik.implementations.lut import p18 as lut_p18

    tab = impl.table
    ix, iy, neg = typical_cells(impl)
    sym = f"_{impl.problem.name}_p18"
    at = lut_p18.Asm(sym).at
    macs = []
    for o in range(2):
        e = tab.ent[o]
        dx, dy, dxy = e[iy, ix + 1] - e[iy, ix], e[iy + 1, ix] - e[iy, ix], e[iy + 1, ix + 1] - e[iy + 1, ix]
        diffs = {"xy": (dx, dy, dxy), "x": (dx,), "y": (dy,)}[tab.dep[o]]
        macs.append([float(np.mean((d & 0x8000) != 0)) for d in diffs])
    odd = [float(np.mean(tab.flips(neg, o))) for o in range(2)]
    out, prev, o = [], "", 0
    for kind, ln in items:
        if kind == "asm" and ln.startswith("bra ") and "_L" in ln:
            m = re.match(r"btfss (\S+), (\d), B", prev)
            if m is None:
                return None
            reg, bit = m.group(1), int(m.group(2))
            if reg == at("d", 1) and macs[o]:
                out.append(macs[o].pop(0))
            elif reg == at("ng"):
                out.append(odd[bit])
                o = bit + 1
            elif reg in (at("v", 2), at("v", 6)):
                out.append(float(np.mean(neg[:, 0 if reg == at("v", 2) else 1])))
            else:
                return None
            if reg == at("d", 1) and not macs[o] and not tab.odd[o].any():
                o += 1  # no odd negation closes this output
        prev = ln if kind == "asm" else ""
    return out if all(not m for m in macs) else None


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
