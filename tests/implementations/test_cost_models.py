"""The families' cost models (poly, poly's wide path, lut, hybrid) against simavr and gpsim
(nnik.bench.costs), configurations drawn as `nnik search` draws them.

* Every claimed band is the measured one (the recorded check, nnik/calibration/*.json) and at
  most 3 %; an estimate states it (``cycles_error_pct``).
* CI, on simavr: every shipped scenario with one family each (the families in turn, poly32 included), and random
  machines (hypothesis, seeded, NNIK_HYPOTHESIS_MACHINES examples) with every family; on gpsim a
  sample of two.  Each measured error is within the band the estimate states.  `make bench`
  measures every family on every scenario and more machines on both chips
  (python3 -m nnik.bench.costs)."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik.bench import costs
from nnik.implementations.cost_band import GOAL_PCT, stated_band

EXAMPLES = int(os.environ.get("NNIK_HYPOTHESIS_MACHINES", "2"))
KINDS = tuple(costs.KINDS)
TARGETS = ("avr", "pic18")


def _cal(kind: str) -> dict:
    return json.loads(costs._cal_path(kind).read_text())


# the targets on which a kind's band must be recorded: every kind has an AVR and a PIC18 body
# (test_every_kind_builds_for_both_chips), so each is checked against simavr and gpsim
CHECKED_ON = {kind: TARGETS for kind in KINDS}
OPEN: dict[str, str] = {}  # kind -> why its band is still over 3 % (xfail strict); none open


@pytest.mark.parametrize("kind", [pytest.param(k, marks=pytest.mark.xfail(strict=True, reason=f"issue 25 part 4 open: "
                                                                           f"{OPEN[k]}")) if k in OPEN else k
                                  for k in KINDS])
def test_every_claimed_band_is_measured_and_within_3_percent(kind):
    cal = _cal(kind)
    chk = cal["check"]["targets"]
    assert set(CHECKED_ON[kind]) <= set(chk), (kind, sorted(chk))
    for t, s in chk.items():
        assert s["band_pct"] == costs.band_of(s["max_abs_pct"]), (kind, t)
        assert s["cases"] >= 3, (kind, t)
        assert stated_band(cal, t) == s["band_pct"]
        assert s["band_pct"] <= GOAL_PCT, (kind, t, s)


def test_every_kind_builds_for_both_chips():
    """Each kind's cost model prices a body of its own on each chip (so each is checked on both)."""
    cal = {k: _cal(k) for k in KINDS}
    for kind in ("lut", "hybrid"):
        assert set(cal[kind]["targets"]) == set(TARGETS), kind
    p = costs.problem_of(costs.DATASETS / "galvo_cba2012.toml")
    for kind in KINDS:
        fam, cfg = costs.draw_config(p, kind, np.random.default_rng(3))
        impl = costs.fit(p, fam, cfg)
        for t in TARGETS:
            e = impl.estimate(t)
            assert e["cycles"] > 0 and e["cycles_error_pct"] is not None, (kind, t)


def test_lut_prices_pic18_sign_tests_by_how_often_they_run():
    """The lut's PIC18 body corrects a multiply-accumulate when the table difference is negative:
    a monotone table (corexy) never does, and is priced so; the other blocks by their inputs."""
    from nnik.implementations.lut import cost as lc
    from nnik.implementations.lut.c import table_ctx

    p = costs.problem_of(costs.DATASETS / "corexy_nonlinear.toml")
    impl = costs.fit(p, *costs.draw_config(p, "lut", np.random.default_rng(1)))
    items = impl.p18_items(table_ctx(impl.problem, impl.table))
    taken = lc.p18_taken(impl, items)
    n_blocks = sum(1 for k, ln in items if k == "asm" and ln.startswith("bra ") and "_L" in ln)
    assert taken is not None and len(taken) == n_blocks and all(0.0 <= x <= 1.0 for x in taken)
    assert min(taken) == 0.0
    half, _ = lc.p18_static(items)
    priced, _ = lc.p18_static(items, taken)
    assert priced != half
    assert lc.p18_static(items, [0.5] * n_blocks)[0] != half  # a run block skips its branch: not the half count


def test_a_check_states_its_band():
    cal = {"check": {"targets": {"avr": {"band_pct": 9.5}}}}
    assert stated_band(cal, "avr") == 9.5 and stated_band(cal, "pic18") is None and stated_band(None, "avr") is None


@pytest.fixture(scope="module")
def chips():
    from nnik.targets import available

    for t in TARGETS:
        ok, why = available(t)
        if not ok:
            pytest.skip(why)


IN_BAND = KINDS  # every family states a measured band, each at most 3 %


def _within_band(rows):
    assert rows
    for r in rows:
        assert r["bit_exact"], r
        assert abs(r["err_pct"]) <= (r["stated_pct"] if r["stated_pct"] is not None else GOAL_PCT), r


@pytest.mark.parametrize("i,scenario", list(enumerate(costs.SCENARIOS)))
def test_shipped_scenarios_on_simavr(chips, tmp_path, i, scenario):
    kind = IN_BAND[i % len(IN_BAND)]
    probs = {scenario: costs.problem_of(costs.DATASETS / f"{scenario}.toml")}
    _within_band(costs.check(probs, [kind], ["avr"], 1, seed=i, workdir=tmp_path, say=lambda m: None))


SETTINGS = dict(deadline=None, database=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@settings(max_examples=EXAMPLES, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1))
def test_random_machines_on_simavr(chips, tmp_path_factory, seed):
    wd = tmp_path_factory.mktemp("costs")
    probs = costs.random_problems(1, seed, wd / "m")
    _within_band(costs.check(probs, IN_BAND, ["avr"], 1, seed=seed, workdir=wd, say=lambda m: None))


def test_a_sample_on_gpsim(chips, tmp_path):
    rng = np.random.default_rng(7)
    scenarios = [costs.SCENARIOS[int(k)] for k in rng.choice(len(costs.SCENARIOS), 2, replace=False)]
    probs = {s: costs.problem_of(costs.DATASETS / f"{s}.toml") for s in scenarios}
    kinds = [IN_BAND[int(k)] for k in rng.choice(len(IN_BAND), 2, replace=False)]
    rows = []
    for (label, p), kind in zip(probs.items(), kinds):
        rows += costs.check({label: p}, [kind], ["pic18"], 1, seed=11, workdir=tmp_path, say=lambda m: None)
    _within_band(rows)


@settings(max_examples=1, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1))
def test_lut_on_gpsim_within_its_recorded_pic18_band(chips, tmp_path_factory, seed):
    """lut prices PIC18's sign tests by how often typical inputs take them (lut.cost.p18_taken):
    a random machine's estimate states the recorded pic18 band and holds it on gpsim."""
    wd = tmp_path_factory.mktemp("lut18")
    rows = costs.check(costs.random_problems(1, seed, wd / "m"), ["lut"], ["pic18"], 1, seed=seed, workdir=wd,
                       say=lambda m: None)
    assert rows and all(r["stated_pct"] is not None for r in rows), rows
    _within_band(rows)


@settings(max_examples=1, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1))
def test_poly_on_gpsim_within_its_recorded_pic18_band(chips, tmp_path_factory, seed):
    """poly prices PIC18's sign tests by how often typical inputs take them: a random machine's
    estimate states the recorded pic18 band and holds it on gpsim."""
    wd = tmp_path_factory.mktemp("poly18")
    rows = costs.check(costs.random_problems(1, seed, wd / "m"), ["poly"], ["pic18"], 1, seed=seed, workdir=wd,
                       say=lambda m: None)
    assert rows and all(r["stated_pct"] is not None for r in rows), rows
    _within_band(rows)
