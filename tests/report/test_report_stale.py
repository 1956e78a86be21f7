"""A verification result belongs to the C it ran: once the C changes, the report stops showing it."""

from __future__ import annotations

from nnik import pipeline
from nnik.report import load_metrics, summary_rows
from nnik.report.inputs import STALE
from tests.bad_input import copy_run, tiny_run  # noqa: F401 (fixture)


def test_emptied_header_is_no_longer_bit_exact(tiny_run, tmp_path):
    run = copy_run(tiny_run, tmp_path / "run")
    pipeline.verify(run, "host")
    m = load_metrics(run)
    assert m["host"]["bit_exact"] and m["host"]["c_hash"]
    h = run / pipeline.MLP_DIR / "galvo_cba2012.h"
    h.write_text("")
    m = load_metrics(run)
    assert m["host"] == {"not_run": STALE}
    rows = {r[0]: r for r in summary_rows(m)}
    assert rows["mlp C on host"][1] == "not run"


def test_changed_c_hides_target_results(tiny_run, tmp_path):
    run = copy_run(tiny_run, tmp_path / "run")
    pipeline.verify(run, "host")
    m = pipeline.load_metrics(run)
    m["targets"] = {"avr": {"cycles": 881.0, "bit_exact": True, "mismatches": 0, "c_hash": m["host"]["c_hash"]}}
    pipeline.write_metrics(run, m, merge=False)
    assert load_metrics(run)["targets"]["avr"]["cycles"] == 881.0
    c = run / pipeline.MLP_DIR / "galvo_cba2012.c"
    c.write_text(c.read_text() + "\n/* edited */\n")
    assert load_metrics(run)["targets"]["avr"] == {"not_run": STALE}
