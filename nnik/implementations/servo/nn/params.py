"""The neural controllers' params (JSON-serialisable; stored in servo/gains.json). Integers are the
truth: no float is stored. Keys:

    "w1"        per net, 8 x 4 int32 master words (Q3.28, |w| <= 2^30), row j = hidden unit j;
                nn_axes has 2 nets (x, y), nn_vector 1
    "w2"        per net, 8 int32 master words (Q3.28 of the normalised output, |w| <= 2^29)
    "eta_shift" 0 .. 27: the learning rate is 2^(1 - eta_shift) in real units (formats.py)
    "jacobian"  per axis (x, y), int16 Q12: the plant's normalised impulse Jacobian (nn_axes: the
                delta's factor; nn_vector: both > 0, they set the split's asymmetry gains)
    "in_shift"  per input (4), -12 .. 12: input i in Q3.12 is raw_i * 2^in_shift[i], saturated
    "win"       (optional, default 4) nn_axes: the reference speed's window in ticks (1, 2, 4, 8)
    "r_shift"   (optional, default 3) nn_vector: |R| is taken of the reference >> r_shift (each
                component saturated to int16 first)
    "w1_every"  (optional, default 2) 1, 2, 4 or 8 ticks: how often a hidden unit's first-layer row
                learns. 1 is the seed's schedule (every row every tick); with N, tick k since the reset
                updates the rows j with j mod N = k mod N (8 / N rows a tick), each row then learning
                from every N-th tick's error. The output layer learns every tick either way. The
                default is the most learning whose worst tick fits the chip's cycle budget (nn_axes
                12,000, nn_vector 7,000 cycles) with a margin: measured on simavr, worst tick over long
                random runs, about 11,200 and 6,750 cycles at 2, 13,900 and 8,150 at 1 (the seed's
                schedule does not fit); 4 and 8 learn less for fewer cycles.

initial_params(kind, cfg, seed, jacobian) makes a seeded random start for pretraining.
"""

from __future__ import annotations

import math

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.servo.nn import formats as f
from nnik.implementations.servo.window import WINDOWS

NETS = {"nn_axes": 2, "nn_vector": 1}
OPTIONAL = {"nn_axes": {"win": 4, "w1_every": 2}, "nn_vector": {"r_shift": 3, "w1_every": 2}}
W1_EVERY = (1, 2, 4, 8)
REQUIRED = ("w1", "w2", "eta_shift", "jacobian", "in_shift")


def _int_list(kind: str, name: str, v, n: int, lo: int, hi: int) -> list[int]:
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise NnikError(f"{kind} params: {name} must be a list of {n}, not {v!r:.60}")
    return [f.check_int(f"{name}[{k}]", x, lo, hi) for k, x in enumerate(v)]


def check_params(kind: str, params) -> dict:
    """params with the optional keys defaulted, every value checked against its format; one
    NnikError line for the first problem."""
    if not isinstance(params, dict):
        raise NnikError(f"{kind} params must be a table, not {type(params).__name__}")
    known = REQUIRED + tuple(OPTIONAL[kind])
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise NnikError(f"{kind} params: unknown key {unknown[0]!r} (known: {', '.join(known)})")
    missing = [k for k in REQUIRED if k not in params]
    if missing:
        raise NnikError(f"{kind} params: missing {missing[0]!r}")
    p = {**OPTIONAL[kind], **params}
    n = NETS[kind]
    w1 = p["w1"]
    if not isinstance(w1, (list, tuple)) or len(w1) != n:
        raise NnikError(f"{kind} params: w1 must be a list of {n} nets")
    out = {"w1": [[_int_list(kind, f"w1[{k}][{j}]", row, f.N_IN, -f.W1_LIM, f.W1_LIM)
                   for j, row in enumerate(_rows(kind, net, k))] for k, net in enumerate(w1)]}
    if not isinstance(p["w2"], (list, tuple)) or len(p["w2"]) != n:
        raise NnikError(f"{kind} params: w2 must be a list of {n} nets")
    out["w2"] = [_int_list(kind, f"w2[{k}]", net, f.N_HID, -f.W2_LIM, f.W2_LIM) for k, net in enumerate(p["w2"])]
    out["eta_shift"] = f.check_int("eta_shift", p["eta_shift"], 0, f.ETA_MAX)
    out["jacobian"] = _int_list(kind, "jacobian", p["jacobian"], 2, -f.I16, f.I16)
    out["in_shift"] = _int_list(kind, "in_shift", p["in_shift"], f.N_IN, -f.IN_SHIFT_MAX, f.IN_SHIFT_MAX)
    if p["w1_every"] not in W1_EVERY:
        raise NnikError(f"{kind} params: w1_every must be one of {', '.join(map(str, W1_EVERY))} ticks, "
                        f"not {p['w1_every']!r}")
    out["w1_every"] = int(p["w1_every"])
    if kind == "nn_axes":
        if p["win"] not in WINDOWS:
            raise NnikError(f"nn_axes params: win must be one of {', '.join(map(str, WINDOWS))} ticks, not {p['win']!r}")
        out["win"] = int(p["win"])
    else:
        out["r_shift"] = f.check_int("r_shift", p["r_shift"], 0, 15)
        if min(out["jacobian"]) <= 0:
            raise NnikError(f"nn_vector params: both Jacobians must be > 0 (the split divides by them), not {out['jacobian']}")
    return out


def _rows(kind: str, net, k: int):
    if not isinstance(net, (list, tuple)) or len(net) != f.N_HID:
        raise NnikError(f"{kind} params: w1[{k}] must be {f.N_HID} rows of {f.N_IN}")
    return net


def jacobian_q(j: float) -> int:
    """A normalised Jacobian as the int16 Q12 integer of params["jacobian"]."""
    if not math.isfinite(j) or abs(round(j * (1 << f.Q_J))) > f.I16:
        raise NnikError(f"Jacobian {j!r} outside the Q12 range +-{f.I16 / (1 << f.Q_J):.4g}")
    return round(j * (1 << f.Q_J))


def default_in_shift(cfg) -> list[int]:
    """Input scales from the encoder's resolution: an error of about 1 mm is 1.0 in Q3.12; its
    per-tick difference 4x finer, the second difference 16x; the fourth input as the error."""
    counts_per_mm = 1000.0 / float(getattr(cfg, "um_per_count", 2.5))
    s = int(round(math.log2(4096.0 / counts_per_mm)))
    clip = lambda v: max(-f.IN_SHIFT_MAX, min(f.IN_SHIFT_MAX, v))  # noqa: E731
    return [clip(s), clip(s + 2), clip(s + 4), clip(s)]


def initial_params(kind: str, cfg, seed: int, jacobian=(1.0, 1.0), eta_shift: int = 12,
                   in_shift: list[int] | None = None) -> dict:
    """A seeded random start (numpy default_rng(seed)): w1 uniform in +-1/sqrt(4) (Xavier-like for
    4 inputs), w2 uniform in +-1/8 of the normalised output; deterministic."""
    if kind not in NETS:
        raise NnikError(f"unknown neural controller kind {kind!r} (known: {', '.join(NETS)})")
    rng = np.random.default_rng(seed)
    n = NETS[kind]
    one = 1 << f.MASTER_FRAC
    w1 = [[[int(round(v * one)) for v in rng.uniform(-0.5, 0.5, f.N_IN)] for _ in range(f.N_HID)] for _ in range(n)]
    w2 = [[int(round(v * one)) for v in rng.uniform(-0.125, 0.125, f.N_HID)] for _ in range(n)]
    p = {"w1": w1, "w2": w2, "eta_shift": int(eta_shift), "jacobian": [jacobian_q(float(j)) for j in jacobian],
         "in_shift": list(in_shift) if in_shift is not None else default_in_shift(cfg),
         **OPTIONAL[kind]}
    return check_params(kind, p)
