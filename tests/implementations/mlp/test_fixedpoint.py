"""Quantisation and the Python integer model (the oracle every C build is compared with)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from nnik.implementations.mlp import quantize as fx
from nnik.implementations.mlp.fixedpoint import round_half_up_shift_vec
from nnik.machine.data import Dataset
from nnik.machine.domain import round_half_up_shift
from nnik.errors import NnikError
from nnik.implementations.mlp.train import TrainedModel


def test_rounding_shift_is_c_semantics_on_negatives():
    v = np.array([-5, -4, -3, -2, -1, 0, 1, 2, 3, 5], dtype=np.int64)
    # C: (v + 1) >> 1 with arithmetic shift = floor((v + 1) / 2)
    np.testing.assert_array_equal(round_half_up_shift(v, 1), np.floor((v + 1) / 2).astype(np.int64))
    np.testing.assert_array_equal(round_half_up_shift_vec(np.array([[-7, 9]]), np.array([0, 2])), [[-7, 2]])


@pytest.fixture(scope="module")
def galvo_model(galvo_run):
    return TrainedModel.load(galvo_run / "model.pt"), Dataset.load(galvo_run / "data.npz")


def test_galvo_fixed_error_bounds(galvo_fixed):
    f = galvo_fixed["fixed"]
    assert max(f["max_abs"]) <= 0.5, f["max_abs"]  # pre-rounding: never more than 1 microstep from exact
    assert max(f["delivered_max_abs"]) <= 1.0, f["delivered_max_abs"]
    # fixed point may not be much worse than float: goal fixed <= float + 0.1
    assert max(f["max_abs"]) <= max(galvo_fixed["float"]["max_abs"]) + 0.1


def test_corexy_residual_fixed_error_bounds(corexy_fixed):
    f = corexy_fixed["fixed"]
    assert max(f["max_abs"]) <= 0.5, f["max_abs"]
    assert max(f["delivered_max_abs"]) <= 1.0, f["delivered_max_abs"]
    assert f["q_formats"]["output"]["affine_G"][0][0] > 0  # the affine base is computed in integers


def test_range_proof_holds_on_dense_sample(galvo_fixed, corexy_fixed):
    for m in (galvo_fixed, corexy_fixed):
        ranges = m["fixed"]["ranges"]
        assert all(r["within_bound"] for r in ranges)
        accs = [r for r in ranges if r["tensor"].startswith(("acc", "total"))]
        assert all(r["bound"] < 2**31 for r in accs)
        assert all(r["headroom_bits"] >= 1.0 for r in accs)


def test_input_stage_never_reaches_2_15(galvo_model):
    model, _ = galvo_model
    im = fx.quantize(model)
    lo, hi = im.inp.lo, im.inp.hi
    corners = np.array([[lo[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    trace = {}
    im.run(corners, trace)
    assert max(abs(trace["X"][0]), abs(trace["X"][1])) <= 32767
    assert trace["X"][1] >= 32700  # and uses the range


def test_clamping_flags_and_no_extrapolation(galvo_model):
    model, _ = galvo_model
    im = fx.quantize(model)
    lo, hi = im.inp.lo, im.inp.hi
    pts = np.array([[hi[0], hi[1]], [hi[0] + 5000, hi[1] + 99999], [lo[0], 0], [lo[0] - 1, 0]])
    _, out, flags = im.run(pts)
    np.testing.assert_array_equal(flags, [0, 1, 0, 1])
    np.testing.assert_array_equal(out[0], out[1])  # clamped, not extrapolated
    np.testing.assert_array_equal(out[2], out[3])


def test_refit_does_not_hurt(galvo_model):
    model, ds = galvo_model
    calib = fx.calibration_set(model, ds.p["train"], ds.q["train"])
    in_um = np.rint(ds.p["test"] * 1000).astype(np.int64)
    from nnik.machine.data import exact_targets

    truth = exact_targets(model.scenario, in_um / 1000)
    rms, mx = {}, {}
    for refit in (False, True):
        im = fx.quantize(model, refit=refit, calib=calib)
        e = np.abs(im.pre_rounding(in_um) - truth)
        rms[refit], mx[refit] = np.sqrt((e**2).mean()), e.max()
    # the refit minimises the squared error on the calibration grid, not on this test set: on a
    # well-trained model it may not gain, but it must not cost anything material
    assert rms[True] <= rms[False] * 1.05, rms
    assert mx[True] <= mx[False] + 0.05, mx


def test_weight_overflow_is_a_clear_error(galvo_model):
    model, _ = galvo_model
    with torch.no_grad():
        w = model.net.net[0].weight
        saved = w.clone()
        w[0, 0] = 1e6
        try:
            with pytest.raises(NnikError, match="hidden layer 1: weights? .*(too large|overflows)"):
                fx.quantize(model)
        finally:
            w.copy_(saved)


def test_no_normalize_model_is_refused(galvo_model):
    model, _ = galvo_model
    model.normalize = False
    try:
        with pytest.raises(NnikError, match="normalised"):
            fx.quantize(model)
    finally:
        model.normalize = True


def test_int8_weights_option(galvo_model):
    model, ds = galvo_model
    im16 = fx.quantize(model, weight_bits=16)
    im8 = fx.quantize(model, weight_bits=8)
    assert np.abs(im8.hidden[0].W).max() <= 127 and np.abs(im8.out.V).max() <= 127
    assert im8.weights_bytes() < im16.weights_bytes()
    assert im8.model_hash() != im16.model_hash()


# ---- the fast kernel (nnik.kernel): its own formats, same accuracy budget ---------------------
def _fast(model_and_ds):
    model, ds = model_and_ds
    return fx.quantize(model, calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]), kernel="fast")


def _errors(model_and_ds, im):
    from nnik.machine.data import exact_targets

    model, ds = model_and_ds
    in_um = np.rint(ds.p["test"] * 1000).astype(np.int64)
    truth = exact_targets(model.scenario, in_um / 1000)
    total, delivered, _ = im.run(in_um)
    pre = np.abs(total / 2.0**im.out.F - truth).max()
    float_err = np.abs(model.predict(in_um / 1000) - truth).max()
    return pre, np.abs(delivered - truth).max(), float_err


def test_kernel_option_is_validated(galvo_model):
    model, _ = galvo_model
    with pytest.raises(NnikError, match="unknown kernel"):
        fx.quantize(model, kernel="turbo")
    assert fx.quantize(model).kernel == "portable"  # the default stays the portable kernel
    assert fx.quantize(model).model_hash() == fx.quantize(model, kernel="portable").model_hash()


def test_fast_kernel_galvo_accuracy_and_formats(galvo_model):
    from nnik.implementations.mlp import kernel as kern

    im = _fast(galvo_model)
    assert im.kernel == "fast"
    pre, delivered, float_err = _errors(galvo_model, im)
    assert pre <= 0.3, pre  # the goal (budget 0.5)
    assert delivered <= 1.0, delivered
    assert pre <= float_err + 0.1
    L = im.hidden[0]
    # layer 1 reads um >> K directly; the tanh input is the top half of the accumulator (or
    # one bit away from it, when the pre-activations reach 1 and the headroom bit moves f),
    # and the tanh table is indexed by its top byte
    assert L.in_frac == 0 and (im.inp.M == 1).all() and (im.inp.S == 0).all()
    assert L.sh in (15, 16) and L.tanh_step == 8 and not L.saturate and L.tanh_m in (0, 1)
    st = kern.ulerp_stats(L.tanh_m, L.tanh_step)
    assert st["max_lsb"] <= kern.FAST_TANH_BUDGET_LSB and st["monotone"]
    assert im.tanh_summary()["max_lsb"] == st["max_lsb"] and im.tanh_bytes() == st["table_bytes"]
    assert im.model_hash() != fx.quantize(galvo_model[0]).model_hash()


def test_fast_kernel_corexy_accuracy(corexy_run):
    model_and_ds = TrainedModel.load(corexy_run / "model.pt"), Dataset.load(corexy_run / "data.npz")
    im = _fast(model_and_ds)
    pre, delivered, _ = _errors(model_and_ds, im)
    assert pre <= 0.5, pre  # the same budget as the portable kernel (test_corexy_residual_fixed_error_bounds)
    assert delivered <= 1.0, delivered
    assert im.out.residual and im.out.G.min() > 0  # the affine base is computed in integers


def test_fast_kernel_range_proof(galvo_model):
    im = _fast(galvo_model)
    rows = fx.range_report(im, fx.dense_inputs_um(im, 121))
    assert all(r["within_bound"] for r in rows)
    assert all(r["headroom_bits"] >= 1.0 for r in rows if r["tensor"].startswith(("acc", "total")))
    tin = next(r for r in rows if r["tensor"].startswith("tanh_in"))
    L = im.hidden[0]
    assert tin["bound"] <= 32767 and tin["tensor"].endswith(f"(Q{L.tanh_m}.{L.tanh_frac})")


def test_fast_tanh_tables():
    from nnik.implementations.mlp import kernel as kern

    T = np.arange(-32768, 32768)
    for m, s in ((0, 8), (1, 8), (2, 7), (3, 6), (3, 8)):
        tab = kern.ulerp_table(m, s)
        assert tab.size == (1 << (16 - s)) + 1 and tab.min() >= 1 and tab.max() <= 65535
        assert (np.diff(tab) >= 0).all()
        h = kern.ulerp_eval(T, tab, s)
        assert np.abs(h).max() <= 32767
        err = np.abs(h - np.tanh(T / 2.0 ** (15 - m)) * 32768)
        assert err.max() == pytest.approx(kern.ulerp_stats(m, s)["max_lsb"])
        assert np.abs(h[1:] + kern.ulerp_eval(-T[1:], tab, s)).max() <= 2  # odd up to rounding
    # the formats the quantiser picks stay within the budget
    assert kern.ulerp_stats(1, 8)["max_lsb"] <= kern.FAST_TANH_BUDGET_LSB
    assert kern.ulerp_stats(3, 8)["max_lsb"] > kern.FAST_TANH_BUDGET_LSB  # why Q3.12 uses a finer step
    with pytest.raises(NnikError):
        kern.ulerp_table(4, 8)


def test_fast_kernel_saturating_layer_is_exact_in_python(galvo_model):
    """Large layer-1 weights: T is clamped where the integer bound says it can leave int16."""
    model, _ = galvo_model
    with torch.no_grad():
        w = model.net.net[0].weight
        saved = w.clone()
        w.mul_(20.0)
        try:
            im = fx.quantize(model, kernel="fast")
        finally:
            w.copy_(saved)
    L = im.hidden[0]
    assert L.saturate and L.tanh_m == 3
    trace = {}
    im.run(fx.dense_inputs_um(im, 81), trace)
    assert trace["tanh_clamps0"] > 0 and max(abs(v) for v in trace["T0"]) <= 32767
