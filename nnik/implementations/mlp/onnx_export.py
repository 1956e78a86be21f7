"""ONNX export of the trained network, checked against torch with onnxruntime."""

from __future__ import annotations

import io
import json
import warnings
from pathlib import Path

import numpy as np
import onnx
import onnxruntime as ort
import torch

from nnik.errors import NnikError
from nnik.implementations.mlp.train import TrainedModel

ONNX_TOLERANCE = 1e-6  # normalised output units


def export_onnx(model: TrainedModel, path: Path) -> None:
    """Write the network (normalised input -> standardised output); the scaling goes in metadata."""
    from nnik.files.atomic_write import write_file_atomic

    write_file_atomic(path, _onnx_bytes(model))  # whole or not at all


def _onnx_bytes(model: TrainedModel) -> bytes:
    net = model.net.eval()
    dummy = torch.zeros(1, net.shape[0], dtype=torch.float64)
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the TorchScript exporter announces its deprecation
        torch.onnx.export(
            net, (dummy,), buf, dynamo=False, input_names=["x_normalized"], output_names=["y_standardized"],
            dynamic_axes={"x_normalized": {0: "n"}, "y_standardized": {0: "n"}}, opset_version=17,
        )
    m = onnx.load_from_string(buf.getvalue())
    meta = {"scenario": model.scenario.name, "unit": model.scenario.unit, "outputs": model.scenario.outputs,
            "scaling": model.scaling.to_dict()}
    onnx.helper.set_model_props(m, {"nnik": json.dumps(meta)})
    onnx.checker.check_model(m)
    return m.SerializeToString()


def check_onnx(model: TrainedModel, path: Path, p_mm: np.ndarray) -> float:
    """Max |onnxruntime - torch| over the points, in standardised output units."""
    xn = model.scaling.normalize(p_mm)
    if not Path(path).is_file():
        raise NnikError("ONNX model not found (run `nnik train` again)", str(path))
    try:
        sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        y_ort = sess.run(None, {"x_normalized": xn})[0]
    except Exception as exc:  # onnxruntime raises its own types for corrupt or foreign models
        reason = str(exc).splitlines()[0][:120] if str(exc) else ""
        raise NnikError(f"corrupt or foreign ONNX model ({type(exc).__name__}: {reason}); run `nnik train` again",
                        str(path)) from None
    if y_ort.shape != (len(xn), model.net.shape[-1]):
        raise NnikError(f"ONNX model gives outputs of shape {y_ort.shape}, not the trained network's", str(path))
    with torch.no_grad():
        y_torch = model.net(torch.from_numpy(xn)).numpy()
    return float(np.abs(y_ort - y_torch).max())
