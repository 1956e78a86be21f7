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
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field

import numpy as np

from nnik.implementations.mlp import tanh as activations
from nnik.implementations.mlp import kernel as kern
from nnik.machine.data import exact_targets
from nnik.machine.domain import domain_um, round_half_up_shift
from nnik.errors import NnikError
from nnik.implementations.mlp.train import TrainedModel

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


# ---- quantisation ----------------------------------------------------------------------------
def _input_stage(model: TrainedModel, fast: bool = False) -> InputStage:
    ws = model.scenario.workspace
    lo, hi = domain_um(ws)
    mid = (lo + hi) // 2
    half_um = model.scaling.in_half * 1000.0
    maxd = np.maximum(hi - mid, mid - lo)
    Ks, Ms, Ss = [], [], []
    for j in range(len(lo)):
        K = 0
        while ((maxd[j] + ((1 << K) >> 1)) >> K) > I16_MAX:
            K += 1
        r = 2.0 ** (15 + K) / half_um[j]  # Q15 counts per pre-shifted um
        if r > I16_MAX / 2:
            raise NnikError(f"workspace axis {j} is too small for micrometre inputs ({2 * half_um[j]:.1f} um)")
        S = 1
        while round(r * 2 ** (S + 1)) <= I16_MAX and S < 30:
            S += 1
        M = int(round(r * 2**S))
        dk_max = (int(maxd[j]) + ((1 << K) >> 1)) >> K
        while ((dk_max * M + (1 << (S - 1))) >> S) > I16_MAX:
            M -= 1  # never let the domain edge round up to 2^15
        if fast:  # layer 1 takes u = (d + 2^(K-1)) >> K itself; its weights carry the scale
            M, S = 1, 0
        Ks.append(K)
        Ms.append(M)
        Ss.append(S)
    return InputStage(lo, hi, mid, np.array(Ks), np.array(Ms), np.array(Ss))


def _pick_frac(Wf: np.ndarray, bf: np.ndarray | None, in_abs, wmax: int, bias_frac_offset: int, what: str,
               max_frac: int = MAX_FRAC, half_exp: int = 3) -> int:
    """Largest f with |W 2^f| <= wmax and every row's worst-case accumulator below ACC_LIMIT.

    f may go down to MIN_FRAC (a weight step of 2^-f > 1) so that int8 weights can hold large values.
    in_abs: the inputs' largest magnitude (a scalar, or one per input column); the bias is in
    Q(f + bias_frac_offset); 2^(f + half_exp) bounds the rounding constant added before the shift.
    """
    if np.abs(Wf).max() > wmax * 2.0**-MIN_FRAC:
        raise NnikError(f"{what}: weight {np.abs(Wf).max():.4g} overflows int{16 if wmax > 127 else 8} "
                        "(retrain with a smaller network or more regularisation)")
    for f in range(max_frac, MIN_FRAC - 1, -1):
        W = np.rint(Wf * 2.0**f)
        if np.abs(W).max() > wmax:
            continue
        bound = (np.abs(W) * in_abs).sum(1)
        if bf is not None:
            bound = bound + np.abs(np.rint(bf * 2.0 ** (f + bias_frac_offset)))
        if bound.max() + 2.0 ** (f + half_exp) < ACC_LIMIT:
            return f
    raise NnikError(f"{what}: no Q format keeps the int32 accumulator from overflowing")


def quantize(model: TrainedModel, tanh_variant: str | None = None, weight_bits: int = 16,
             refit: bool = True, calib: tuple[np.ndarray, np.ndarray] | None = None,
             kernel: str | None = None) -> IntegerModel:
    """Quantise a trained model. calib = (p_mm, q_units) used for the integer-aware output refit.

    kernel: "portable" (default) or "fast" (see nnik.kernel: layer 1 on um >> K, tanh input
    formats chosen so the tanh input is the top half of the accumulator, a byte-indexed tanh
    table).  With kernel="fast", tanh_variant=None selects the fast tanh table; naming a
    variant keeps that variant (tanh input Q3.12).
    """
    scn = model.scenario
    if not model.normalize:
        raise NnikError("fixed-point export needs a model trained on normalised inputs "
                        "(--no-normalize models exist only for the seed 004 comparison)", scn.source)
    kernel = kern.check_kernel(kernel)
    fast = kernel == "fast"
    fast_tanh = fast and tanh_variant is None
    variant = activations.get_variant(tanh_variant).name
    wmax = I16_MAX if weight_bits == 16 else 127
    inp = _input_stage(model, fast)
    layers = model.net.dense_layers()
    z_lo, z_hi = -np.ones(2), np.ones(2)  # IBP box in normalised units
    hidden: list[HiddenLayer] = []
    for li, (Wf, bf) in enumerate(layers[:-1]):
        c, r = (z_lo + z_hi) / 2, (z_hi - z_lo) / 2
        zc, zr = Wf @ c + bf, np.abs(Wf) @ r
        zl, zh = zc - zr, zc + zr
        if fast:
            hidden.append(_fast_hidden(model, inp, li, Wf, bf, wmax, weight_bits, fast_tanh, (zl, zh)))
        else:
            f = _pick_frac(Wf, bf, I16_MAX, wmax, ACT_FRAC, f"hidden layer {li + 1}")
            if f + ACT_FRAC - TANH_IN_FRAC < 1:
                raise NnikError(f"hidden layer {li + 1}: weights up to {np.abs(Wf).max():.4g} are too large for "
                                f"int{weight_bits} storage with a Q3.12 tanh input")
            W = np.rint(Wf * 2.0**f).astype(np.int64)
            B = np.rint(bf * 2.0 ** (ACT_FRAC + f)).astype(np.int64)
            acc_bound = int((np.abs(W).sum(1) * I16_MAX + np.abs(B)).max())
            # the tanh clamp is needed where the float range (plus rounding slack) can reach 8
            saturate = bool(max(abs(zl.min()), abs(zh.max())) + 0.01 >= 8.0)
            hidden.append(HiddenLayer(W, B, f, f + ACT_FRAC - TANH_IN_FRAC, saturate, acc_bound,
                                      (float(zl.min()), float(zh.max()))))
        z_lo, z_hi = np.tanh(zl), np.tanh(zh)
    if fast_tanh:
        variant = "+".join(dict.fromkeys(kern.ulerp_name(L.tanh_m, L.tanh_step) for L in hidden))
    shape = list(model.net.shape)
    im = IntegerModel(scn.name, scn.unit, scn.outputs, variant, weight_bits, inp, hidden, None, shape,
                      kernel=kernel)
    im.out = _output_layer(model, im, layers[-1], wmax, refit, calib)
    return im


def _fast_hidden(model, inp: InputStage, li: int, Wf, bf, wmax: int, weight_bits: int, fast_tanh: bool,
                 z) -> HiddenLayer:
    """A hidden layer of the fast kernel (see nnik.kernel)."""
    what = f"hidden layer {li + 1}"
    if li == 0:
        # inputs u = (d + 2^(K-1)) >> K (um, int16): fold the normalisation into the weights
        s = model.scaling
        half_um = s.in_half * 1000.0
        Wq = Wf * (2.0 ** inp.K / half_um)[None, :]
        bq = bf + Wf @ ((inp.mid - s.in_center * 1000.0) / half_um)
        in_frac = 0
        maxd = np.maximum(inp.hi - inp.mid, inp.mid - inp.lo)
        in_abs = np.array([(int(m) + ((1 << int(k)) >> 1)) >> int(k) for m, k in zip(maxd, inp.K)], dtype=np.int64)
    else:
        Wq, bq, in_frac, in_abs = Wf, bf, ACT_FRAC, np.int64(I16_MAX)
    f = _pick_frac(Wq, bq, in_abs, wmax, in_frac, what, max_frac=MAX_FRAC + ACT_FRAC - in_frac,
                   half_exp=in_frac - TANH_IN_FRAC)
    W = np.rint(Wq * 2.0**f).astype(np.int64)
    B = np.rint(bq * 2.0 ** (in_frac + f)).astype(np.int64)
    acc_bound = int(((np.abs(W) * in_abs).sum(1) + np.abs(B)).max())

    def sh_of(m: int) -> int:
        return in_frac + f - (15 - m)

    def t_bound(m: int) -> int:
        sh = sh_of(m)
        return (acc_bound + (1 << (sh - 1))) >> sh

    fits = [m for m in range(4) if sh_of(m) >= 1 and t_bound(m) <= I16_MAX]
    if fast_tanh:
        m, step = kern.choose_tanh_format(sh_of, fits[0] if fits else 3)
    else:
        m, step = 3, 0  # a portable variant: its Q3.12 contract
    if sh_of(m) < 1:
        raise NnikError(f"{what}: weights up to {np.abs(Wf).max():.4g} are too large for int{weight_bits} "
                        f"storage with a Q{m}.{15 - m} tanh input")
    zl, zh = z
    return HiddenLayer(W, B, f, sh_of(m), m not in fits, acc_bound, (float(zl.min()), float(zh.max())),
                       in_frac=in_frac, tanh_frac=15 - m, tanh_step=step, t_bound=min(t_bound(m), I16_MAX + 1))


def _output_layer(model, im, last, wmax, refit, calib) -> OutputLayer:
    s = model.scaling
    scn = model.scenario
    Wf, bf = last
    n_out = Wf.shape[0]
    residual = scn.network["mode"] == "residual"
    half_um = s.in_half * 1000.0
    center_um = s.in_center * 1000.0
    # float model in the integer coordinates: q = W' h + b' + A d, d = in - mid (um)
    Wp = s.out_std[:, None] * Wf
    A = s.base_coef / half_um[None, :] if residual else np.zeros((n_out, 2))
    bp = s.out_std * bf + s.out_mean + s.base_intercept + (s.base_coef @ ((im.inp.mid - center_um) / half_um) if residual else 0)
    if refit and calib is not None:
        p_mm, q = calib
        in_um = np.rint(p_mm * 1000).astype(np.int64)
        h, d, _ = im.forward_hidden(in_um)
        cols = [h / 2.0**ACT_FRAC] + ([d.astype(np.float64)] if residual else []) + [np.ones((len(q), 1))]
        Phi = np.hstack(cols)
        colscale = np.abs(Phi).max(0)
        colscale[colscale == 0] = 1
        sol, *_ = np.linalg.lstsq(Phi / colscale, q, rcond=None)
        sol = sol / colscale[:, None]
        nh = h.shape[1]
        Wp = sol[:nh].T
        if residual:
            A = sol[nh:nh + 2].T
        bp = sol[-1]
    maxd = np.maximum(im.inp.hi - im.inp.mid, im.inp.mid - im.inp.lo).astype(np.float64)
    bound_units = np.abs(Wp).sum(1) + np.abs(bp) + np.abs(A) @ maxd + 1.0
    F = MAX_FRAC
    while F > 0 and bound_units.max() * 2.0**F * 1.001 >= ACC_LIMIT:
        F -= 1
    if bound_units.max() * 2.0**F >= ACC_LIMIT:
        raise NnikError(f"outputs up to {bound_units.max():.4g} {scn.unit} overflow int32")
    g = _pick_frac(Wp, None, I16_MAX, wmax, 0, "output layer")
    V = np.rint(Wp * 2.0**g).astype(np.int64)
    mlp_bound = int((np.abs(V).sum(1) * I16_MAX).max())
    e = ACT_FRAC + g - F
    if e < 0 and mlp_bound * 2 ** (-e) >= ACC_LIMIT:
        raise NnikError("output layer: the MLP term overflows its int32 scaling")
    C = np.rint(bp * 2.0**F).astype(np.int64)
    A1 = np.zeros((n_out, 2), np.int64)
    A0 = np.zeros((n_out, 2), np.int64)
    P = np.zeros((n_out, 2), np.int64)
    G = np.zeros((n_out, 2), np.int64)
    if residual:
        # the fast kernel prefers G = 16: floor(d A / 2^16) is then bytes 2..5 of a 48-bit
        # product in its assembly (the C keeps the split form below; both are exact)
        g_order = ([AFFINE_FAST_G] if im.kernel == "fast" else []) + list(range(40, -1, -1))
        for k in range(n_out):
            for j in range(2):
                P_max = int(np.floor(np.log2(ACC_LIMIT / (maxd[j] + 1))))
                for Gk in g_order:
                    a = int(np.rint(A[k, j] * 2.0 ** (F + Gk)))
                    p = min(P_max, Gk)
                    a1 = a >> p
                    if abs(a1) * (maxd[j] + 1) < ACC_LIMIT:
                        A1[k, j], A0[k, j], P[k, j], G[k, j] = a1, a - (a1 << p), p, Gk
                        break
    total_bound = int(bound_units.max() * 2.0**F)
    return OutputLayer(V, g, F, C, A1, A0, P, G, residual, mlp_bound, total_bound, scn.actuator.code_range)


# ---- range analysis: the proof ---------------------------------------------------------------
def range_report(im: IntegerModel, dense_in_um: np.ndarray) -> list[dict]:
    """Per tensor: analytic integer bound, observed range on a dense sample, headroom bits."""
    trace: dict = {}
    im.run(dense_in_um, trace)
    if im.kernel == "fast":
        maxd = np.maximum(im.inp.hi - im.inp.mid, im.inp.mid - im.inp.lo)
        u_max = max((int(m) + ((1 << int(k)) >> 1)) >> int(k) for m, k in zip(maxd, im.inp.K))
        rows = [{"tensor": "u (layer-1 input, um >> K)", "bound": u_max, "observed": list(trace["X"])}]
    else:
        rows = [{"tensor": "X (Q15 input)", "bound": I16_MAX, "observed": list(trace["X"])}]
    for li, L in enumerate(im.hidden):
        rows.append({"tensor": f"acc{li + 1} (Q{L.in_frac + L.f})", "bound": L.acc_bound,
                     "observed": list(trace[f"acc{li}"]), "float_preactivation": list(L.z_interval)})
        if L.t_bound:
            t_bound = I16_MAX if L.saturate else L.t_bound
        else:
            t_bound = I16_MAX if L.saturate else int(-(-L.acc_bound >> L.sh))
        rows.append({"tensor": f"tanh_in{li + 1} (Q{L.tanh_m}.{L.tanh_frac})", "bound": t_bound,
                     "observed": list(trace[f"T{li}"]), "clamp_emitted": L.saturate,
                     "clamps_in_sample": int(trace.get(f"tanh_clamps{li}", 0))})
        rows.append({"tensor": f"h{li + 1} (Q15)", "bound": I16_MAX, "observed": list(trace[f"H{li}"])})
    rows.append({"tensor": f"acc_out (Q{15 + im.out.g})", "bound": im.out.mlp_bound, "observed": list(trace["acc_out"])})
    rows.append({"tensor": f"total (Q{im.out.F})", "bound": im.out.total_bound, "observed": list(trace["total"])})
    for r in rows:
        obs = max(abs(r["observed"][0]), abs(r["observed"][1]))
        r["within_bound"] = bool(obs <= r["bound"])
        r["headroom_bits"] = float(np.log2(I32_LIMIT / max(r["bound"], 1)))
    return rows


def dense_inputs_um(im: IntegerModel, n: int = 201) -> np.ndarray:
    """A dense grid over the domain (corners included), in um."""
    xs = np.linspace(im.inp.lo[0], im.inp.hi[0], n).round().astype(np.int64)
    ys = np.linspace(im.inp.lo[1], im.inp.hi[1], n).round().astype(np.int64)
    g = np.stack(np.meshgrid(xs, ys, indexing="xy"), -1).reshape(-1, 2)
    return g


def calibration_set(model: TrainedModel, p_train: np.ndarray, q_train: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points for the integer-aware refit: a dense exact grid for analytic machines, else the training rows."""
    scn = model.scenario
    if scn.mechanism.analytic:
        p = np.rint(np.concatenate([scn.workspace.grid(121), p_train]) * 1000) / 1000  # whole um, as the C sees them
        return p, exact_targets(scn, p)
    return p_train, q_train


__all__ = ["IntegerModel", "quantize", "range_report", "dense_inputs_um", "calibration_set"]
