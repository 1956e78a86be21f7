"""Training on the shipped scenarios meets the foundation's accuracy targets (float, vs exact IK)."""

from __future__ import annotations

import json

import numpy as np
import onnxruntime as ort
import torch

from nnik import pipeline
from nnik.machine.data import Dataset
from nnik.machine.scenario import load_scenario
from nnik.implementations.mlp.train import TrainedModel, train_model
from tests.conftest import DATASETS


def test_galvo_cba2012_float_within_quarter_microstep(galvo_run):
    m = json.loads((galvo_run / "metrics.json").read_text())
    assert m["unit"] == "microstep" and m["outputs"] == ["alpha", "beta"]
    assert m["network"]["shape"] == [2, 6, 2]
    assert max(m["float"]["max_abs"]) <= 0.25, m["float"]
    assert m["onnx"]["max_abs_diff"] <= 1e-6
    for key in ("max_abs", "rms", "p99"):
        assert len(m["float"][key]) == 2


def test_corexy_residual_beats_affine(corexy_run):
    m = json.loads((corexy_run / "metrics.json").read_text())
    assert m["network"]["mode"] == "residual"
    assert max(m["float"]["max_abs"]) <= 0.5, m["float"]
    assert min(m["affine_only"]["max_abs"]) >= 3.0, m["affine_only"]  # the scenario proves something


def test_model_file_loads_weights_only_and_predicts_the_same(galvo_run):
    blob = torch.load(galvo_run / "model.pt", weights_only=True)
    assert "state_dict" in blob and blob["scenario_raw"]["name"] == "galvo_cba2012"
    model = TrainedModel.load(galvo_run / "model.pt")
    ds = Dataset.load(galvo_run / "data.npz")
    pred = model.predict(ds.p["test"][:100])
    assert np.abs(pred - ds.q["test"][:100]).max() < 0.25


def test_onnx_agrees_with_torch(galvo_run):
    model = TrainedModel.load(galvo_run / "model.pt")
    sess = ort.InferenceSession(str(galvo_run / "model.onnx"))
    xn = np.random.default_rng(0).uniform(-1, 1, (1000, 2))
    y = sess.run(None, {"x_normalized": xn})[0]
    with torch.no_grad():
        ref = model.net(torch.from_numpy(xn)).numpy()
    assert np.abs(y - ref).max() <= 1e-6
    meta = {p.key: p.value for p in __import__("onnx").load(str(galvo_run / "model.onnx")).metadata_props}
    assert json.loads(meta["nnik"])["scenario"] == "galvo_cba2012"


def _quick(tmp_path, name, normalize=None):
    scn = load_scenario(DATASETS / f"{name}.toml")
    scn.training.update(restarts=1)
    pipeline.generate(scn, tmp_path)
    return scn, Dataset.load(tmp_path / "data.npz"), normalize


def test_training_is_deterministic(tmp_path):
    """Same seed, same weights (with a budget too large to cut the run short)."""
    scn, ds, _ = _quick(tmp_path, "galvo_cba2012")
    scn.training.update(adam_steps=200, lbfgs_rounds=3)
    a = train_model(scn, ds, progress=False).net.state_dict()
    b = train_model(scn, ds, progress=False).net.state_dict()
    for k in a:
        assert torch.equal(a[k], b[k])


def test_no_normalize_reproduces_seed004_effect(tmp_path):
    """Raw mm inputs saturate the tanh units: the error grows by a large factor (seed 004 Table 1)."""
    scn, ds, _ = _quick(tmp_path, "hbot_unicamp")
    scn.training.update(adam_steps=1500, lbfgs_rounds=40)
    raw = train_model(scn, ds, normalize=False, progress=False).predict(ds.p["test"])
    norm = train_model(scn, ds, normalize=True, progress=False).predict(ds.p["test"])
    err_raw = np.abs(raw - ds.q["test"]).mean()
    err_norm = np.abs(norm - ds.q["test"]).mean()
    assert err_raw > 5 * err_norm, (err_raw, err_norm)
