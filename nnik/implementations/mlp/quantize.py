"""The Q-format analysis of an MLP: :func:`quantize` turns a trained float MLP into an
:class:`~nnik.implementations.mlp.fixedpoint.IntegerModel` (formats from interval bounds over the
input box, the output layer refitted on the integer activations), and :func:`range_report`
checks the bounds on a dense sample (see :mod:`nnik.implementations.mlp.fixedpoint` for the data
path)."""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.mlp import kernel as kern
from nnik.implementations.mlp import tanh as activations
from nnik.implementations.mlp.fixedpoint import (ACC_LIMIT, ACT_FRAC, AFFINE_FAST_G, I16_MAX, I32_LIMIT, MAX_FRAC,
                                                  MIN_FRAC, TANH_IN_FRAC, HiddenLayer, InputStage, IntegerModel,
                                                  OutputLayer)
from nnik.implementations.mlp.train import TrainedModel
from nnik.machine.data import exact_targets
from nnik.machine.domain import domain_um


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
