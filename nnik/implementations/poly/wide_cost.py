"""Cycles and flash of the `poly` family's wide path (``width = 32``): a linear model in the
structure of the C (codegen/templates/poly32_ik.c.j2), calibrated on simavr and gpsim.

What a call of NAME_mac(a, b, K, f) costs, and why each count is a feature:

* ``calls``: the 32 x 32 -> 64 product (16 MUL / MULWF), the same for every call.
* ``bits``: the last ``f % 8`` one-bit shifts of five bytes (AVR: every call, inlined; PIC18: the
  bit loop of NAME_bits, for 0 < f < 32).
* ``high``: calls whose byte pick starts in the top word (f >= 32): AVR picks sign bytes (cheaper),
  PIC18 takes nnik_sar32 of the high word instead of NAME_bits.
* ``negs``: the expected number of negative operands per evaluation (each one is a 32-bit
  subtraction of the sign correction). The operands' signs depend on the input, so this is their
  mean over a grid of the domain (the simulators' figure is the mean over random in-domain
  inputs); the weights are known, so it is computed from the program itself.
* ``k_adds``, ``l_adds``: the constant K (a 64-bit add) and L (a 32-bit add) where they are not 0.
* AVR, the outputs' final rounding shift ``nnik_sar32(n + 2^(s-1), s)``: avr-gcc moves whole
  bytes for s in {8, 16, 24}, has short forms for 1 and 31, and loops bit by bit for the rest. Its
  cycles are known, not fitted: the shift microbenchmark's ``rs`` table of the avr-gcc -Os profile
  (nnik/calibration/avr-gcc-Os.json, measured on simavr by the MLP estimator's calibration).
* ``clamps``: outputs clamped to the actuator's code range (two 32-bit compares each).
* ``f0_calls``: PIC18, calls with f = 0, which return the low word and skip NAME_bits (its byte
  copy and call) altogether.
* ``sar_bytes``, ``sar_bits``: on SDCC every nnik_sar32 (the outputs' shift, and the high word's
  shift by f - 32 of a call with f >= 32) moves whole bytes in a loop, then bits in another.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

FEATURES = {"avr": ("calls", "bits", "high", "negs", "k_adds", "l_adds", "clamps"),
            "pic18": ("calls", "bits", "high", "negs", "k_adds", "l_adds", "sar_bits", "sar_bytes", "clamps",
                      "f0_calls")}
FLASH_FEATURES = {"avr": ("calls", "bits", "k_adds", "l_adds"), "pic18": ("calls", "k_adds", "l_adds")}
GRID = 41  # points per axis of the domain grid the operands' signs are averaged over
SHIFT_TABLE = Path(__file__).resolve().parents[2] / "calibration" / "avr-gcc-Os.json"


@functools.cache
def _avr_rounding_shift_cycles() -> tuple[float, ...]:
    return tuple(json.loads(SHIFT_TABLE.read_text())["shift_tables"]["cycles"]["rs"])


def known_cycles(impl, target: str) -> float:
    """Cycles known from a measured table rather than fitted (AVR: the outputs' rounding shifts)."""
    if target != "avr":
        return 0.0
    tab = _avr_rounding_shift_cycles()
    return float(sum(tab[o.s] for o in impl.prog.outs))


def _calls(impl, x: np.ndarray, y: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, int, int, object]]:
    """(a, b, f, K, L) of every NAME_mac call, a and b evaluated at the inputs (x, y)."""
    vals = {"u": x - impl.maps[0].c, "v": y - impl.maps[1].c}

    def get(b):
        return vals[b] if isinstance(b, str) else np.int64(b)

    calls = []
    for st in impl.prog.steps:
        a, b = vals[st.a], get(st.b)
        calls.append((a, b, int(st.f), int(st.K), st.L))
        vals[st.dst] = ((a * b + np.int64(st.K)) >> st.f) + (get(st.L) if st.L is not None else 0)
    for o in impl.prog.outs:
        calls += [(vals[A], get(B), int(t), 0, None) for A, B, t in o.terms]
    return calls


def domain_grid(impl) -> tuple[np.ndarray, np.ndarray]:
    p = impl.problem
    gx = np.rint(np.linspace(p.lo[0], p.hi[0], GRID)).astype(np.int64)
    gy = np.rint(np.linspace(p.lo[1], p.hi[1], GRID)).astype(np.int64)
    x, y = np.meshgrid(gx, gy, indexing="xy")
    return x.ravel(), y.ravel()


def counts(impl, target: str, inputs: tuple[np.ndarray, np.ndarray] | None = None) -> dict:
    """The model's features (see the module docstring); ``negs`` averaged over ``inputs`` (clamped
    (x, y); default: a grid of the domain)."""
    x, y = domain_grid(impl) if inputs is None else inputs
    calls = _calls(impl, np.asarray(x, dtype=np.int64), np.asarray(y, dtype=np.int64))
    n = len(x)
    negs = sum(np.mean(np.broadcast_to(a, (n,)) < 0) + np.mean(np.broadcast_to(b, (n,)) < 0) for a, b, *_ in calls)
    shifts = [o.s for o in impl.prog.outs]
    sar = shifts + [c[2] - 32 for c in calls if c[2] >= 32]
    bits = [f & 7 for _, _, f, _, _ in calls if (target == "avr" or 0 < f < 32)]
    return {"calls": len(calls), "bits": sum(bits), "high": sum(1 for c in calls if c[2] >= 32), "negs": float(negs),
            "f0_calls": sum(1 for c in calls if c[2] == 0), "k_adds": sum(1 for c in calls if c[3] != 0), "l_adds": sum(1 for c in calls if c[4] is not None),
            "known": known_cycles(impl, target),
            "clamps": len(shifts) if impl.problem.code_range is not None else 0,
            "sar_bits": sum(s & 7 for s in sar), "sar_bytes": sum(s >> 3 for s in sar)}


def predict(coef: list[float], c: dict, feats: tuple[str, ...], known: float = 0.0) -> float:
    return float(coef[0] + sum(w * c[f] for w, f in zip(coef[1:], feats)) + known)


def fit(rows: list[dict], target: str) -> dict:
    """Least squares of measured cycles and flash on the features, each row weighted by 1 / its
    cycles (relative error is what the band states); rows: {target: {counts..., cycles, flash_bytes}}."""
    out = {}
    for key, what, feats in (("cycles", "cycles", FEATURES[target]), ("flash", "flash_bytes", FLASH_FEATURES[target])):
        x = np.array([[1.0] + [r[target][f] for f in feats] for r in rows])
        y = np.array([r[target][what] for r in rows])
        known = np.array([r[target]["known"] if key == "cycles" else 0.0 for r in rows])
        w = 1.0 / y
        out[key] = np.linalg.lstsq(x * w[:, None], (y - known) * w, rcond=None)[0].tolist()
    return out
