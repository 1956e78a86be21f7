"""A failing export leaves c/ exactly as it was; a successful one replaces every file."""

from __future__ import annotations

import pytest

from nnik.implementations.mlp import quantize as fx
from nnik import pipeline
from nnik.files.atomic_write import Staged
from nnik.errors import NnikError
from tests.bad_input import copy_run, snapshot, tiny_run  # noqa: F401 (fixture)


def test_failing_export_changes_nothing(tiny_run, tmp_path, monkeypatch):
    run = copy_run(tiny_run, tmp_path / "run")
    before = snapshot(run / "c")
    assert before  # the tiny run exported once
    real = fx.range_report

    def broken(im, pts):
        return [{**r, "within_bound": False} for r in real(im, pts)]

    # a different kernel choice would rewrite every file; the failure must stop all of it
    monkeypatch.setattr(fx, "range_report", broken)
    with pytest.raises(NnikError, match="range analysis failed"):
        pipeline.export(run)
    assert snapshot(run / "c") == before
    assert not [p for p in run.rglob(".staging-*")]


def test_staged_commit_writes_everything(tmp_path):
    st = Staged(tmp_path / "out")
    st.add({"a.c": "int a;\n", "a.h": "extern int a;\n"}, "x/y")
    st.add({"b.c": "int b;\n"}, ".", runtime_headers=False)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    st.commit()
    assert (tmp_path / "out" / "x" / "y" / "a.h").read_text() == "extern int a;\n"
    assert (tmp_path / "out" / "x" / "y" / "nnik_flash.h").is_file()
    assert (tmp_path / "out" / "b.c").read_text() == "int b;\n"
    assert not list((tmp_path / "out").glob(".staging-*"))
