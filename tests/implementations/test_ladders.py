"""Target-driven ladders (issue 15): symmetry belongs to the IK, not the field; tables grow to
the flash budget of the target and the chip; a polynomial's degree grows until the fit stalls;
with nothing that meets the target, every family's best is still written."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik import pipeline
from nnik.errors import NnikError
from nnik.implementations.accuracy import accuracy
from nnik.implementations.lut.family import LutImpl, cell_ladder, table_budget, table_entries
from nnik.implementations.lut.table import MAX_NODES, dependence, fold_plan
from nnik.implementations.poly.family import _symmetry
from nnik.selection import _stalled
from tests.bad_input import copy_run, tiny_run  # noqa: F401 (fixture)
from tests.implementations.lut_helpers import host_check, problem_from

SHORT_THROW = """name = "short_throw"
[mechanism]
kind = "galvo_gimbal"
z_mm = {z}
[actuator]
kind = "stepper"
[workspace]
x_mm = [{x0}, {x1}]
y_mm = [{y0}, {y1}]
[target]
max_error = 0.05
{extra}
"""


def gimbal(tmp_path, z=120.0, x=(-60.0, 100.0), y=(-70.0, 40.0), extra=""):
    p = tmp_path / "g.toml"
    p.write_text(SHORT_THROW.format(z=z, x0=x[0], x1=x[1], y0=y[0], y1=y[1], extra=extra))
    return problem_from(p)


def test_an_asymmetric_field_keeps_the_gimbals_symmetry(tmp_path):
    p = gimbal(tmp_path)
    lo, hi, mirror = p.parity_box
    assert mirror == (True, True) and list(hi) == [100_000, 70_000] and list(lo) == [-100_000, -70_000]
    alpha, beta = _symmetry(p)
    assert alpha.indep_x and alpha.classes == frozenset({(0, 1)})  # odd in y, no x
    assert beta.classes == frozenset({(1, 0)})  # odd in x, even in y
    fold, odd = fold_plan(p, True)
    assert fold == (True, True) and odd.tolist() == [[False, True], [True, False]]
    # the folded table covers the farther edge of each axis and is exact in the C
    im = LutImpl.fit(p, {"k": [12, 12]})
    assert im.table.grid.span == (100_000, 70_000)
    acc = accuracy(im)
    assert acc["pre_max"] < 0.05
    r = host_check(im, tmp_path)
    assert r["bit_exact"] and r["mismatches"] == 0


def test_a_field_off_zero_has_no_fold(tmp_path):
    p = gimbal(tmp_path, x=(10.0, 90.0))
    assert p.parity_box[2] == (False, True)
    assert fold_plan(p, True)[0] == (False, True)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(span=st.tuples(st.integers(1_000, 4_000_000), st.integers(1_000, 4_000_000)),
       budget=st.integers(64, 64 * 1024), dep=st.sampled_from([("xy", "xy"), ("y", "xy"), ("xy", "x")]))
def test_the_table_ladder_stops_at_the_flash_budget_not_at_a_node_count(span, budget, dep):
    span = list(span)
    ks = cell_ladder(span, budget, dep)
    for k in ks:
        assert 2 * table_entries(span, k, dep) <= budget
        assert max((span[a] >> k[a]) + 2 for a in range(2)) <= MAX_NODES
    if ks and ks[-1] != [0, 0]:  # it stopped because the next halving no longer fits
        nxt = [max(0, v - 1) for v in ks[-1]]
        assert (2 * table_entries(span, nxt, dep) > budget
                or max((span[a] >> nxt[a]) + 2 for a in range(2)) > MAX_NODES)


def test_the_lut_ladder_grows_with_the_flash_limit(tmp_path):
    small = gimbal(tmp_path, extra="max_flash_bytes = 1500")
    big = gimbal(tmp_path / ".." / tmp_path.name, extra="")
    assert table_budget(small) == 1500 and table_budget(big) == 16 * 1024
    dep = dependence(big, True)
    biggest = max(table_entries(LutImpl.stored_span(big), c["k"], dep) for c in LutImpl.ladder(big))
    assert max(table_entries(LutImpl.stored_span(small), c["k"], dep) for c in LutImpl.ladder(small)) * 2 <= 1500
    assert biggest * 2 > 4 * 1500  # the default budget reaches tables a 40-node cap would not
    assert all(c["bits"] == 16 or 4 * table_entries(LutImpl.stored_span(big), c["k"], dep) <= 16 * 1024
               for c in LutImpl.ladder(big))


def test_a_grown_knob_stops_once_the_fit_stalls():
    assert _stalled("degree", {"degree": 4}, {1: 1.0, 2: 0.5, 3: 0.2}) is None
    assert _stalled("degree", {"degree": 6}, {1: 1.0, 2: 0.5, 3: 0.2, 4: 0.1, 5: 0.05}) is None
    why = _stalled("degree", {"degree": 7}, {1: 1.0, 2: 0.5, 3: 0.2, 4: 0.19, 5: 0.185, 6: 0.3})
    assert why is None or "did not improve" in why
    why = _stalled("degree", {"degree": 6}, {1: 1.0, 2: 0.5, 3: 0.2, 4: 0.19, 5: 0.185})
    assert why and "degree 4, 5 did not improve" in why
    assert _stalled(None, {"degree": 9}, {1: 1.0}) is None


COARSE = [{"k": [18, 18], "bits": 16, "W": 8, "fit": "lsq", "symmetry": True},
          {"k": [17, 17], "bits": 16, "W": 8, "fit": "lsq", "symmetry": True}]


@pytest.fixture
def coarse_tables(monkeypatch):
    """A lut ladder of 2 nodes per axis (a plane per cell): nothing on it meets 0.25 microstep on the galvo."""
    monkeypatch.setattr(LutImpl, "ladder", classmethod(lambda cls, problem: [dict(c) for c in COARSE]))


def test_nothing_meets_the_default_target_still_picks_and_writes_every_best(tiny_run, tmp_path, coarse_tables):
    """tiny_run's scenario has no [target]: when no configuration meets the default max_error,
    the most accurate verified family best is the pick, marked as a miss."""
    out = copy_run(tiny_run, tmp_path / "run")
    sec = pipeline.select(out, families=["lut"], progress=False)
    assert not sec["max_error_asked"] and not sec["pick_meets_max_error"]
    row = next(r for r in sec["implementations"] if r["picked"])
    assert row["pre_max"] > sec["target"]["max_error"] and row["flash_bytes"]["avr"]
    assert (out / "c" / "alt" / "lut" / "galvo_cba2012.c").is_file() and (out / "c" / "galvo_cba2012.c").is_file()
    assert (out / "c" / "galvo_cba2012.c").read_text() == (out / "c" / "alt" / "lut" / "galvo_cba2012.c").read_text()


def test_a_target_asked_for_and_missed_says_what_would_reach_it(tiny_run, tmp_path, coarse_tables):
    out = copy_run(tiny_run, tmp_path / "run")
    with pytest.raises(NnikError) as exc:
        pipeline.select(out, families=["lut"], target={"max_error": 0.25, "max_flash_bytes": 60}, progress=False)
    msg = str(exc.value)
    assert "closest is lut" in msg and "raise [target] max_flash_bytes (60 B)" in msg
    # every family's best is still written and measured
    assert (out / "c" / "alt" / "lut" / "galvo_cba2012.c").is_file()
    m = json.loads((out / "metrics.json").read_text())
    assert m["selection"]["pick"] is None and m["selection"]["implementations"][0]["targets"]["avr"]["bit_exact"]
