"""OUTDIR's file names, and OUTDIR/metrics.json: read whole, written atomically, each stage
merging its own sections into it."""

from __future__ import annotations

import json
from pathlib import Path

from nnik.errors import NnikError

DATA_FILE = "data.npz"  # the scenario's samples (or its measured rows), labelled
MODEL_FILE = "model.pt"  # the MLP family's trained network (the scenario's own)
ONNX_FILE = "model.onnx"
METRICS_FILE = "metrics.json"
C_DIR = "c"  # the pick (NAME.c), the float IK (NAME_float.c), alt/<family>/ and mlp/
MLP_DIR = "c/mlp"  # the scenario's MLP pipeline (its kernel), and the other kernel in MLP_DIR/<kernel>/
FIXED_EVAL_FILE = "fixed_eval.npz"


def load_metrics(outdir: Path) -> dict:
    path = Path(outdir) / METRICS_FILE
    if not path.is_file():
        raise NnikError("no metrics.json (run `nnik evaluate` first)", str(outdir))
    return read_metrics(path)


def read_metrics(path: Path) -> dict:
    try:
        m = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise NnikError(f"corrupt metrics file ({type(exc).__name__}); run `nnik evaluate` again", str(path)) from None
    if not isinstance(m, dict):
        raise NnikError(f"corrupt metrics file (a JSON {type(m).__name__}, not an object); run `nnik evaluate` again",
                        str(path))
    from nnik.files import json_shape

    json_shape.check(m, json_shape.METRICS, str(path), "run `nnik evaluate` again")
    return m


def write_metrics(outdir: Path, metrics: dict, merge: bool = True) -> None:
    """Write OUTDIR/metrics.json; later steps merge their own sections into it."""
    from nnik.files.atomic_write import write_file_atomic

    path = Path(outdir) / METRICS_FILE
    if path.is_dir():
        raise NnikError("is a directory where nnik writes its metrics; move it away", str(path))
    old = read_metrics(path) if merge and path.is_file() else {}
    old.update(metrics)
    write_file_atomic(path, json.dumps(old, indent=2) + "\n")  # a kill leaves the old file or the new one
