"""The steps `nnik run` chains: generate -> train (+ONNX) -> evaluate. Each reads/writes OUTDIR."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from sklearn.linear_model import LinearRegression

from nnik.data import Dataset, build_dataset
from nnik.errors import NnikError
from nnik.evaluate import error_stats, position_error_um, relative_pct
from nnik.onnx_export import ONNX_TOLERANCE, check_onnx, export_onnx
from nnik.scenario import Scenario
from nnik.train import TrainedModel, train_model

DATA_FILE = "data.npz"
MODEL_FILE = "model.pt"
ONNX_FILE = "model.onnx"
METRICS_FILE = "metrics.json"


def default_outdir(scn: Scenario, normalize: bool = True) -> Path:
    return Path("build") / (scn.name if normalize else f"{scn.name}-no-normalize")


def generate(scn: Scenario, outdir: Path) -> Dataset:
    outdir.mkdir(parents=True, exist_ok=True)
    ds = build_dataset(scn)
    ds.save(outdir / DATA_FILE)
    return ds


def train(scn: Scenario, outdir: Path, normalize: bool | None = None, progress: bool = True) -> TrainedModel:
    ds = Dataset.load(outdir / DATA_FILE)
    model = train_model(scn, ds, normalize=normalize, progress=progress)
    model.save(outdir / MODEL_FILE)
    export_onnx(model, outdir / ONNX_FILE)
    return model


def affine_baseline(ds: Dataset) -> np.ndarray:
    """The skeptic's first baseline: a least-squares affine map fitted on the training set."""
    lr = LinearRegression().fit(ds.p["train"], ds.q["train"])
    return lr.predict(ds.p["test"])


def evaluate(outdir: Path) -> dict:
    model = TrainedModel.load(outdir / MODEL_FILE)
    ds = Dataset.load(outdir / DATA_FILE)
    scn = model.scenario
    p, q = ds.p["test"], ds.q["test"]
    pred = model.predict(p)
    onnx_diff = check_onnx(model, outdir / ONNX_FILE, p)
    if not onnx_diff <= ONNX_TOLERANCE:
        raise NnikError(f"ONNX model differs from torch by {onnx_diff:.3g} (> {ONNX_TOLERANCE:g})", str(outdir / ONNX_FILE))
    shape = list(model.net.shape)
    metrics = {
        "name": scn.name,
        "scenario": scn.source,
        "mechanism": scn.mechanism.describe(),
        "actuator": scn.actuator.describe(),
        "outputs": scn.outputs,
        "unit": scn.unit,
        "network": {
            "shape": shape,
            "mode": scn.network["mode"],
            "normalize": model.normalize,
            "parameters": int(sum(a * b + b for a, b in zip(shape[:-1], shape[1:]))),
        },
        "dataset": {**{f"n_{s}": int(len(ds.p[s])) for s in ds.p}, "truth": ds.meta["truth"]},
        "float": {**error_stats(pred, q), "rel_pct": relative_pct(pred, q)},
        "affine_only": error_stats(affine_baseline(ds), q),
        "onnx": {"max_abs_diff": onnx_diff, "tolerance": ONNX_TOLERANCE, "ok": True},
        "train_seconds": model.train_seconds,
    }
    pos = position_error_um(scn, pred, p)
    if pos is not None:
        metrics["float"]["position_um"] = pos
    write_metrics(outdir, metrics, merge=False)
    return metrics


def write_metrics(outdir: Path, metrics: dict, merge: bool = True) -> None:
    """Write OUTDIR/metrics.json; later steps merge their own sections into it."""
    path = outdir / METRICS_FILE
    old = json.loads(path.read_text()) if merge and path.is_file() else {}
    old.update(metrics)
    path.write_text(json.dumps(old, indent=2) + "\n")
