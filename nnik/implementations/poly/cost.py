"""Static cost of the `poly` family on AVR and PIC18, calibrated against the simulators.

The assembly the generator emits is straight-line code, so its cycles and words are counted
from the instruction list itself (AVR: MUL*/LDS/STD 2 cycles, the rest 1; PIC18: MOVFF and BRA
2, the rest 1, and each sign test by the fraction of typical inputs that take its branch,
``_p18_counts``). What the C around it costs (clamp,
prologue and the registers the assembly makes avr-gcc save, SDCC's pointer I/O, and the DAC
clamps written in C after the assembly, ``c_clamps``: an output whose code range does not fit
the assembly's int16 compare) is a linear model in a few counts, fitted by least squares to simavr/gpsim measurements of fixed reference
configurations. ``nnik/calibration/poly.json`` holds the fit, keyed to the hash of the C those
references emit; ``validated`` says a separate validation set was predicted within 3 % and the
references still emit the same C.

    python -m nnik.implementations.poly.calibrate   # re-measure and rewrite the calibration
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import numpy as np

from nnik.implementations.cost_band import stated_band

CALIBRATION = Path(__file__).resolve().parents[2] / "calibration" / "poly.json"
TOLERANCE = 0.03
ROOT = Path(__file__).resolve().parents[3]

# (scenario, input unit or None for the scenario's own, config)
REFERENCE = [
    ("galvo_cba2012", None, {"degree": 3}),
    ("galvo_cba2012", None, {"degree": 5}),
    ("galvo_dual_xy2", None, {"degree": 5, "split": True, "rounding": False}),
    ("corexy_nonlinear", None, {"degree": 2, "lsb": True, "split": True}),
    ("hbot_unicamp", None, {"degree": 1, "lsb": True}),
    ("poly_ref_offaxis_dac16", None, {"degree": 2, "split": [True, False], "rounding": False}),  # 2 c_clamps on avr
]
VALIDATION = [
    ("galvo_cba2012", None, {"degree": 5, "split": True}),
    ("galvo_dual_xy2", 1.0, {"degree": 5, "split": [True, False]}),
    ("galvo_dual_xy2", None, {"degree": 3}),
    ("corexy_measured", None, {"degree": 2, "lsb": True, "split": True}),
    ("poly_ref_offaxis_dac16", None, {"degree": 6, "coef_bits": 16, "split": True}),  # 1 c_clamp on avr
]
# reference machines that are not shipped scenarios (datasets/) live here
REFERENCE_MACHINES = CALIBRATION.parent / "machines"


# ---- counting the emitted assembly ---------------------------------------------------------------

def _block(src: str, start: str, stop: str) -> list[str]:
    if start not in src:
        return []
    part = src[src.index(start):]
    return part[:part.index(stop)].splitlines()[1:]


def _count(lines: list[str], pattern: str, cycles, words) -> tuple[float, float]:
    """Cycles and words of the instructions in the string literals `lines` (labels skipped)."""
    cyc = wds = 0.0
    for line in lines:
        m = re.match(pattern, line)
        if m and not m.group(1).endswith(":"):
            op = m.group(1).split()[0]
            cyc += cycles(op)
            wds += words(op)
    return cyc, wds


def _avr_counts(src: str) -> dict:
    cyc, words = _count(_block(src, "__asm__ __volatile__ (", '            : "+r"'), r'\s*"(.*)\\n\\t"\s*$',
                        lambda op: 2 if op in ("mul", "muls", "mulsu", "lds", "std") else (1.5 if op.startswith("br") else 1),
                        lambda op: 2 if op == "lds" else 1)
    for k in re.findall(r"_ASR24\((?:x|y), (\d+)\);", src):
        cyc += 3 * int(k)  # the input shift in C: asr/ror/ror a bit
        words += 3 * int(k)
    clob = re.search(r'            : ("r\d+"(?:, "r\d+")*), "memory"', src)
    pushes = sum(1 for r in re.findall(r'"r(\d+)"', clob.group(1)) if 2 <= int(r) <= 17) if clob else 0
    return {"asm_cycles": cyc, "asm_words": words, "pushes": pushes}


_P18_LINE = re.compile(r'\s*"(?:\\t)?(.*)\\n"\s*$')
_P18_OPERAND = re.compile(r"_\w+\+(\d+), 7, B$")


def _p18_cycles(op: str) -> int:
    return 2 if op in ("movff", "bra") else 1


def _p18_counts(src: str, neg: dict[int, float]) -> dict:
    """Expected cycles and words of the assembly block.  Its only conditional code is the sign
    test of an int16 operand: ``btfss X+1, 7`` + ``bra L`` around a correction block (3 cycles
    when X >= 0, 2 + the block when X < 0; neg[X] is the fraction of typical inputs where X < 0)
    and ``btfsc X+1, 7`` + ``setf`` (2 cycles either way)."""
    ins = [m.group(1) for m in map(_P18_LINE.match, _block(src, "    __asm__(", "    );")) if m]
    cyc = words = 0.0
    i = 0
    while i < len(ins):
        op = ins[i].split()[0]
        if op.endswith(":"):
            i += 1
            continue
        words += 2 if op == "movff" else 1
        nxt = ins[i + 1].split()[0] if i + 1 < len(ins) else ""
        if op == "btfss" and nxt == "bra":
            lab = ins[i + 1].split()[1] + ":"
            end = ins.index(lab, i + 2)
            block = [x.split()[0] for x in ins[i + 2:end]]
            words += 1 + sum(2 if b == "movff" else 1 for b in block)
            p = neg[int(_P18_OPERAND.search(ins[i]).group(1)) - 1]
            cyc += 3 + p * (2 + sum(map(_p18_cycles, block)) - 3)
            i = end + 1
        elif op == "btfsc" and nxt == "setf":
            words += 1
            cyc += 2
            i += 2
        else:
            cyc += _p18_cycles(op)
            i += 1
    return {"asm_cycles": cyc, "asm_words": words}


def _p18_negative(impl, n: int = 2000, seed: int = 12345) -> dict[int, float]:
    """Work-area offset -> fraction of typical inputs (uniform in the domain) where that int16 is < 0."""
    from nnik.implementations.poly.int_model import step_values
    from nnik.implementations.poly.p18 import work_offsets

    p = impl.problem
    rng = np.random.default_rng(seed)
    c, _ = p.clamp(np.stack([rng.integers(p.lo[j], p.hi[j] + 1, n) for j in range(2)], 1))
    m0, m1 = impl.maps
    vals = step_values(impl.prog, m0.u(c[:, 0]), m1.u(c[:, 1]), m0.r(c[:, 0]), m1.r(c[:, 1]))
    return {off: float(np.mean(vals[name] < 0)) for name, off in work_offsets(impl.prog).items() if name in vals}


# PIC18 writes its DAC clamp in C only where the range analysis lets an output leave the code
# range; no reference does, so it is counted but not priced there (no recorded pic18 band).
FEATURES = {"avr": ("asm_cycles", "pushes", "lsb", "c_clamps"), "pic18": ("asm_cycles", "lsb")}
FLASH_FEATURES = {"avr": ("asm_words", "pushes", "lsb", "c_clamps"), "pic18": ("asm_words", "lsb")}
_C_CLAMP = re.compile(r"^    if \(out\[\d+\] < ", re.M)  # the DAC clamp in C after the asm block (avr.py, p18.py)


_SECTIONS = {"avr": ("#if defined(NNIK_KERNEL_AVR)", "\n#elif"), "pic18": ("#elif defined(NNIK_KERNEL_P18)", "\n#else")}


def _section(src: str, target: str) -> str:
    """The part of the C that the target's compiler builds (one source holds every path)."""
    start, stop = _SECTIONS[target]
    if start not in src:
        return ""
    part = src[src.index(start):]
    return part[:part.index(stop, len(start))]


def counts(impl, target: str) -> dict:
    from nnik.implementations.poly.c import lsb_used

    src = impl.render_source()
    c = _avr_counts(src) if target == "avr" else _p18_counts(src, _p18_negative(impl))
    c["lsb"] = len(lsb_used(impl.prog))
    c["c_clamps"] = len(_C_CLAMP.findall(_section(src, target)))
    return c


# ---- the estimate -----------------------------------------------------------------------------------

_STATE: dict = {}


def _calibration() -> dict | None:
    if "cal" not in _STATE:
        _STATE["cal"] = json.loads(CALIBRATION.read_text()) if CALIBRATION.exists() else None
    return _STATE["cal"]


def _refs_unchanged(cal: dict, impl_cls) -> bool:
    """The reference configurations still emit the C the calibration measured."""
    if "refs_ok" not in _STATE:
        try:
            _STATE["refs_ok"] = reference_key(impl_cls) == cal.get("key")
        except Exception:  # noqa: BLE001 - a scenario that no longer builds means "not validated"
            _STATE["refs_ok"] = False
    return _STATE["refs_ok"]


def _predict(coef: list[float], c: dict, feats: tuple) -> float:
    return float(coef[0] + sum(w * c[f] for w, f in zip(coef[1:], feats)))


def estimate(impl, target: str) -> dict:
    from nnik.errors import NnikError

    if target not in FEATURES:
        raise NnikError(f"unknown target {target!r} (avr | pic18)")
    cal = _calibration()
    c = counts(impl, target)
    if cal is None:
        return {"cycles": c["asm_cycles"], "flash_bytes": int(2 * c["asm_words"]), "ram_bytes": 0,
                "validated": False}
    t = cal["targets"][target]
    cyc = _predict(t["cycles"], c, FEATURES[target])
    flash = _predict(t["flash"], c, FLASH_FEATURES[target])
    ram = 0 if target == "avr" else 24 + 2 * len(impl.prog.steps)
    ok = bool(cal.get("validated")) and _refs_unchanged(cal, type(impl))
    return {"cycles": cyc, "flash_bytes": int(round(flash)), "ram_bytes": ram, "validated": ok,
            "cycles_error_pct": stated_band(cal, target)}


# ---- the reference configurations (the calibration's key) ---------------------------------------

def reference_impl(impl_cls, scn_name: str, unit, config: dict):
    """One reference configuration fitted by ``impl_cls`` (PolyImpl; passed in, so this module
    does not import the family it serves)."""
    from nnik.machine.data import build_dataset
    from nnik.implementations.problem import Problem
    from nnik.machine.scenario import load_scenario

    key = (scn_name, unit)
    if key not in _STATE.setdefault("problems", {}):
        path = ROOT / "datasets" / f"{scn_name}.toml"
        scn = load_scenario(path if path.exists() else REFERENCE_MACHINES / f"{scn_name}.toml")
        _STATE["problems"][key] = Problem(scn, build_dataset(scn), unit_um=unit or scn.export.get("input_unit_um", 1.0))
    return impl_cls.fit(_STATE["problems"][key], config)


def reference_key(impl_cls) -> str:
    """Hash of the C the reference configurations emit: the calibration holds while it matches."""
    h = hashlib.sha256()
    for name, unit, cfg in REFERENCE:
        h.update(reference_impl(impl_cls, name, unit, cfg).render_source().encode())
    return h.hexdigest()[:16]
