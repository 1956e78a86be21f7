"""The same scenario and seed give the same C, pick, model and figures on an idle machine and with
both cores kept busy (nnik.bench.reproducible does the two runs and the comparison; `make bench`
runs it on the large measured scenario too)."""

from __future__ import annotations

from nnik.bench.reproducible import compare, fingerprint
from tests.bad_input import GALVO, with_training
from tests.conftest import require_tool, write_toml


def test_a_run_under_load_gives_the_same_bytes(tmp_path):
    for tool in ("avr-gcc", "simavr", "gpsim"):
        require_tool(tool)
    toml = write_toml(tmp_path, with_training(GALVO.replace("n_test = 20000", "n_test = 300")))
    r = compare(toml, tmp_path / "work", busy=2)
    assert r["compared"] >= 5  # the C files, pick, model, data, metrics and report at least
    assert r["differences"] == [], r
    assert any(k.startswith("c/") for k in fingerprint(tmp_path / "work" / "out"))


def test_the_comparison_sees_a_changed_figure(tmp_path):
    """The check can fail: one changed figure in a copy of a run is a difference."""
    import json
    import shutil

    src = tmp_path / "a"
    (src / "c").mkdir(parents=True)
    (src / "c" / "ik.c").write_text("int x;\n")
    (src / "metrics.json").write_text(json.dumps({"train_seconds": 1.0, "fixed": {"max": 0.1}}))
    dst = tmp_path / "b"
    shutil.copytree(src, dst)
    (dst / "metrics.json").write_text(json.dumps({"train_seconds": 9.0, "fixed": {"max": 0.1}}))
    assert fingerprint(src) == fingerprint(dst)  # a duration alone is no difference
    (dst / "metrics.json").write_text(json.dumps({"train_seconds": 1.0, "fixed": {"max": 0.2}}))
    assert fingerprint(src) != fingerprint(dst)
