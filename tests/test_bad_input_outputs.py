"""Corrupt or missing files in an output directory (issue 11, section 3): every loader answers
with one line and exit 2, and the directory is left exactly as it was."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from nnik.machine.data import Dataset
from tests.bad_input import copy_run, fails, tiny_run  # noqa: F401  (tiny_run is a fixture)


@pytest.fixture
def run(tiny_run, tmp_path):  # noqa: F811
    return copy_run(tiny_run, tmp_path / "run")


def test_random_model_file(run, capsys):
    (run / "model.pt").write_bytes(np.random.default_rng(0).bytes(5000))
    fails(capsys, ["evaluate", run], "model.pt", "not an nnik model file", watch=run)


@pytest.mark.parametrize("spoil,needle", [
    (lambda b: b.update(shape=[2, 7, 2]), "size mismatch"),
    (lambda b: b.pop("scaling"), "KeyError"),
    (lambda b: b.update(shape="2-6-2"), "ValueError"),
])
def test_mismatched_model_file(run, capsys, spoil, needle):
    blob = torch.load(run / "model.pt", weights_only=True)
    spoil(blob)
    torch.save(blob, run / "model.pt")
    fails(capsys, ["evaluate", run], "model.pt", "corrupt nnik model file", needle, watch=run)


def test_truncated_dataset(run, capsys):
    raw = (run / "data.npz").read_bytes()
    (run / "data.npz").write_bytes(raw[: len(raw) // 2])
    fails(capsys, ["evaluate", run], "data.npz", "not a readable nnik dataset", watch=run)


def test_random_dataset(run, capsys):
    (run / "data.npz").write_bytes(np.random.default_rng(1).bytes(3000))
    fails(capsys, ["evaluate", run], "data.npz", "not a readable nnik dataset", watch=run)


def test_dataset_missing_an_array(run, capsys):
    ds = Dataset.load(run / "data.npz")
    np.savez_compressed(run / "data.npz", meta=np.array(json.dumps(ds.meta)), p_train=ds.p["train"])
    fails(capsys, ["export", run], "data.npz", "KeyError", watch=run)


def test_nan_test_position(run, capsys):
    ds = Dataset.load(run / "data.npz")
    ds.p["test"][3, 0] = np.nan
    ds.save(run / "data.npz")
    fails(capsys, ["evaluate", run], "data.npz", "p_test holds NaN", watch=run)


@pytest.mark.parametrize("command", [["export"], ["verify", "--target", "host"]])
@pytest.mark.parametrize("content,needle", [
    (None, "no metrics.json"),
    ('{"name": "galvo", "unit": ', "corrupt metrics file (JSONDecodeError)"),
    ("[1, 2, 3]", "a JSON list, not an object"),
    ('{"name": "x"}', "metrics.json lacks unit"),
])
def test_bad_metrics(run, capsys, command, content, needle):
    if content is None:
        (run / "metrics.json").unlink()
    else:
        (run / "metrics.json").write_text(content)
    fails(capsys, [command[0], run, *command[1:]], needle, watch=run)


def test_missing_onnx(run, capsys):
    (run / "model.onnx").unlink()
    fails(capsys, ["evaluate", run], "model.onnx", "ONNX model not found", watch=run)


def test_corrupt_onnx(run, capsys):
    raw = (run / "model.onnx").read_bytes()
    (run / "model.onnx").write_bytes(raw[: len(raw) // 3])
    fails(capsys, ["evaluate", run], "model.onnx", "corrupt or foreign ONNX model", watch=run)


def test_c_is_a_file(run, capsys):
    import shutil

    shutil.rmtree(run / "c")
    (run / "c").write_text("not a directory\n")
    fails(capsys, ["export", run], "is a file where nnik writes the directory c/", watch=run)


def test_model_dir_is_a_file(tmp_path, capsys):
    f = tmp_path / "notadir"
    f.write_text("x")
    fails(capsys, ["evaluate", f], "is a file, not an nnik output directory", watch=f)


def test_report_into_an_existing_file(run, capsys):
    target = run / "report.html"
    target.write_text("<p>mine</p>")
    fails(capsys, ["report", run, "-o", target], "report.html", "exists and is not a directory", watch=run)
