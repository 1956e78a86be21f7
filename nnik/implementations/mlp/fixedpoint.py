"""Quantisation: a trained float MLP -> an integer model the C reproduces bit for bit.

Data path (every step is an int16/int32 operation in C, emulated here with numpy int64):

1. clamp in_um to the trained domain [lo, hi] (flag = 1 if clamped); d = in - mid (int32);
2. normalise: dk = (d + 2^(K-1)) >> K (|dk| < 2^15), X = (dk * M + 2^(S-1)) >> S, X in Q15
   (|X| <= 32767 by construction: M is chosen so the edge cannot round to 32768);
3. each hidden layer: acc = B + sum X_j W_ij (int16 x int16 -> int32, W in Q f, B in Q(15+f)),
   T = (acc + 2^(sh-1)) >> sh in Q3.12 (sh = f + 3), clamped to +-32767 only where the range
   analysis says |pre-activation| can reach 8; H = tanh_int(T) in Q15;
4. output k: m = sum H_i V_ki (V in Q g, int32), brought to Q F: e = 15 + g - F,
   m >> e with rounding (e > 0) or m * 2^-e (e <= 0); plus, in residual mode, the exact affine
   base computed from the micrometre input d with a split multiply (two int32 products, no
   int64): floor(d * A / 2^G) = (d * A1 + ((d * A0) >> P)) >> (G - P), A = A1 2^P + A0;
   total = C_k + m + sum_j affine_kj in Q F (int32);
5. delivered = (total + 2^(F-1)) >> F (round half up), clamped to the DAC's codes if any.

Formats come from range analysis: interval bound propagation over the whole input box gives
the float ranges; worst-case integer bounds size every accumulator below 2^31; a dense sample
cross-checks both. The output layer is refitted on the integer hidden activations
(least squares), which absorbs the tanh approximation and layer-1 rounding.

``quantize(..., kernel="fast")`` (nnik.kernel; C from nnik.fastc) changes three choices, the
data path above staying the same sequence of exact integer operations:

* step 2 becomes X = dk itself (M = 1, S = 0): layer 1 multiplies u = (d + 2^(K-1)) >> K,
  its weights carry the normalisation (Q f per um >> K, acc in Q f);
* step 3's T is in Q(m).(15-m), m = 0..3 the fewest integer bits its worst-case bound needs
  (a byte-aligned sh = 16 where that costs at most one bit), and tanh is a byte-indexed
  uniform table (nnik.kernel.ulerp_eval) instead of a portable variant;
* in residual mode the affine base prefers G = 16 (a byte-aligned 48-bit product on 8-bit CPUs).

This module holds the integer model and its evaluation; the quantisation and the range analysis
that choose its formats are in :mod:`nnik.implementations.mlp.quantize`.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field

import numpy as np

from nnik.implementations.mlp import kernel as kern
from nnik.implementations.mlp import tanh as activations
from nnik.machine.domain import round_half_up_shift

I16_MAX = 32767
I32_LIMIT = 2**31 - 1
ACC_LIMIT = 2**30  # keep one bit of headroom on every int32 accumulator
TANH_IN_FRAC = 12
ACT_FRAC = 15
MAX_FRAC = 24
MIN_FRAC = -8
AFFINE_FAST_G = 16


@dataclass
class InputStage:
    lo: np.ndarray  # int64 (n_in,), um
    hi: np.ndarray
    mid: np.ndarray
    K: np.ndarray  # pre-shift per axis
    M: np.ndarray  # multiplier per axis (int16 range)
    S: np.ndarray  # post-shift per axis


@dataclass
class HiddenLayer:
    W: np.ndarray  # int64 (out, in), Q f
    B: np.ndarray  # int64 (out,), Q (15 + f)
    f: int
    sh: int  # acc -> Q3.12
    saturate: bool  # the clamp of T is reachable
    acc_bound: int  # worst-case |acc| over all inputs
    z_interval: tuple[float, float]  # float pre-activation range (IBP)
    in_frac: int = ACT_FRAC  # Q format of the layer's input: 15 (Q15), or 0 (fast layer 1: um >> K)
    tanh_frac: int = TANH_IN_FRAC  # T in Q(15 - tanh_frac).tanh_frac; acc in Q(in_frac + f)
    tanh_step: int = 0  # fast kernel: node step 2^s of the ulerp table (0: a portable variant)
    t_bound: int = 0  # worst-case |T| (before the clamp, if any)

    @property
    def tanh_m(self) -> int:
        return 15 - self.tanh_frac


@dataclass
class OutputLayer:
    V: np.ndarray  # int64 (out, hidden), Q g
    g: int
    F: int  # output format Q F
    C: np.ndarray  # int64 (out,), Q F: bias, output mean, affine intercept
    A1: np.ndarray  # int64 (out, in): affine coefficient split, high part
    A0: np.ndarray  # int64 (out, in): low part, 0 <= A0 < 2^P
    P: np.ndarray  # int64 (out, in)
    G: np.ndarray  # int64 (out, in): A = A1 2^P + A0 ~ coef * 2^(F + G) per um
    residual: bool
    mlp_bound: int
    total_bound: int
    code_range: tuple[int, int] | None  # DAC clamp


@dataclass
class IntegerModel:
    name: str
    unit: str
    outputs: list[str]
    tanh_variant: str
    weight_bits: int
    inp: InputStage
    hidden: list[HiddenLayer]
    out: OutputLayer
    shape: list[int]
    ranges: list[dict] = field(default_factory=list)
    kernel: str = kern.DEFAULT_KERNEL

    # ---- the oracle: every C operation on int64 numpy arrays --------------------------------
    def forward_hidden(self, in_um: np.ndarray, trace: dict | None = None):
        """Input stage and hidden layers -> (h int64 Q15 (N, H), d int64 um offsets, flags)."""
        in_um = np.asarray(in_um, dtype=np.int64)
        x_c, flags = clamp_um_from(in_um, self.inp.lo, self.inp.hi)
        d = x_c - self.inp.mid
        dk = round_half_up_shift_vec(d, self.inp.K)
        X = round_half_up_shift_vec(dk * self.inp.M, self.inp.S)
        _record(trace, "X", X)
        v = X
        for li, L in enumerate(self.hidden):
            acc = v @ L.W.T + L.B
            _record(trace, f"acc{li}", acc)
            T = round_half_up_shift(acc, L.sh)
            if L.saturate:
                n_sat = int(np.count_nonzero(np.abs(T) > I16_MAX))
                T = np.clip(T, -I16_MAX, I16_MAX)
                if trace is not None:
                    trace[f"tanh_clamps{li}"] = trace.get(f"tanh_clamps{li}", 0) + n_sat
            _record(trace, f"T{li}", T)
            v = self._tanh(L, T)
            _record(trace, f"H{li}", v)
        return v, d, flags

    def _tanh(self, L: HiddenLayer, T: np.ndarray) -> np.ndarray:
        if L.tanh_step:
            return kern.ulerp_eval(T, kern.ulerp_table(L.tanh_m, L.tanh_step), L.tanh_step)
        return activations.tanh_int(T, self.tanh_variant).astype(np.int64)

    def run(self, in_um: np.ndarray, trace: dict | None = None):
        """(N, 2) int inputs in um -> (total int64 (N, n_out) in Q F, delivered int64, flags int64)."""
        v, d, flags = self.forward_hidden(in_um, trace)
        o = self.out
        m = v @ o.V.T
        _record(trace, "acc_out", m)
        e = ACT_FRAC + o.g - o.F
        m = round_half_up_shift(m, e) if e > 0 else m * (1 << -e)
        total = o.C + m
        if o.residual:
            for k in range(len(o.C)):
                for j in range(d.shape[1]):
                    hi = d[:, j] * o.A1[k, j] + ((d[:, j] * o.A0[k, j]) >> o.P[k, j])
                    total[:, k] += hi >> (o.G[k, j] - o.P[k, j])
        _record(trace, "total", total)
        out = round_half_up_shift(total, o.F)
        if o.code_range is not None:
            out = np.clip(out, *o.code_range)
        return total, out, flags

    def pre_rounding(self, in_um: np.ndarray) -> np.ndarray:
        total, _, _ = self.run(in_um)
        return total / float(2**self.out.F)

    # ---- bookkeeping ------------------------------------------------------------------------
    def weights_bytes(self) -> int:
        wb = 1 if self.weight_bits == 8 else 2
        n = sum(L.W.size * wb + L.B.size * 4 for L in self.hidden)
        n += self.out.V.size * wb + self.out.C.size * 4
        if self.out.residual:
            n += self.out.A1.size * 4 * 2
        return int(n)

    def tanh_tables(self) -> list[tuple[int, int]]:
        """Distinct (m, s) fast tanh tables the model uses (empty for the portable kernel)."""
        return sorted({(L.tanh_m, L.tanh_step) for L in self.hidden if L.tanh_step})

    def tanh_bytes(self) -> int:
        """Flash bytes of the tanh table(s)."""
        if self.kernel == "fast":
            return int(sum(kern.ulerp_stats(m, s)["table_bytes"] for m, s in self.tanh_tables()))
        return int(activations.get_variant(self.tanh_variant).coeff_bytes)

    def tanh_summary(self) -> dict:
        """{"variant", "max_lsb", "rms_lsb"} of the tanh the model uses (worst table if several);
        for the portable kernel this is activations.sweep(tanh_variant)."""
        if self.kernel == "fast":
            st = [kern.ulerp_stats(m, s) for m, s in self.tanh_tables()]
            worst = max(st, key=lambda r: r["max_lsb"])
            return {"variant": self.tanh_variant, "max_lsb": worst["max_lsb"], "rms_lsb": worst["rms_lsb"]}
        sw = activations.sweep(self.tanh_variant)
        return {"variant": self.tanh_variant, "max_lsb": sw["max_lsb"], "rms_lsb": sw["rms_lsb"]}

    def model_hash(self) -> str:
        d = {"h": [[L.W.tolist(), L.B.tolist(), L.f, L.sh] for L in self.hidden],
             "o": [self.out.V.tolist(), self.out.C.tolist(), self.out.A1.tolist(), self.out.A0.tolist(), self.out.F],
             "i": [self.inp.M.tolist(), self.inp.S.tolist(), self.inp.K.tolist(), self.inp.mid.tolist()],
             "t": self.tanh_variant}
        if self.kernel != "portable":  # portable hashes stay what they were
            d["k"] = [self.kernel, [[L.in_frac, L.tanh_frac, L.tanh_step, L.saturate] for L in self.hidden]]
        blob = json.dumps(d, sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def formats(self) -> dict:
        fast = self.kernel == "fast"
        return {
            "kernel": self.kernel,
            "input": {"Q": "Q0 (um >> K)" if fast else "Q15", "K": self.inp.K.tolist(), "M": self.inp.M.tolist(),
                      "S": self.inp.S.tolist()},
            "hidden": [{"weights": f"Q{L.f}", "bias": f"Q{L.in_frac + L.f}", "acc": f"Q{L.in_frac + L.f}",
                        "tanh_in": f"Q{L.tanh_m}.{L.tanh_frac}", "shift": L.sh, "tanh_clamp": L.saturate,
                        **({"tanh_table": kern.ulerp_name(L.tanh_m, L.tanh_step)} if L.tanh_step else {})}
                       for L in self.hidden],
            "output": {"weights": f"Q{self.out.g}", "total": f"Q{self.out.F}", "affine_G": self.out.G.tolist(),
                       "affine_P": self.out.P.tolist()},
        }


def _record(trace, key, arr):
    if trace is None or arr.size == 0:
        return
    lo, hi = int(arr.min()), int(arr.max())
    if key in trace:
        lo, hi = min(lo, trace[key][0]), max(hi, trace[key][1])
    trace[key] = (lo, hi)


def clamp_um_from(in_um, lo, hi):
    c = np.clip(in_um, lo, hi)
    return c, np.any(c != in_um, axis=1).astype(np.int64)


def round_half_up_shift_vec(v: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Per-column (v + 2^(s-1)) >> s; a column with s = 0 passes through unchanged."""
    shift = np.asarray(shift, dtype=np.int64)
    half = np.where(shift > 0, np.int64(1) << np.maximum(shift - 1, 0), 0)
    return (v + half) >> shift
