"""nnik run's pick: every family behind one interface, verified on the chips, cheapest wins."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nnik import pipeline
from nnik.errors import NnikError
from nnik.implementations import FAMILIES
from tests.conftest import require_tool


@pytest.fixture(scope="module")
def galvo_selected(galvo_run):
    require_tool("simavr")
    require_tool("gpsim")
    sec = pipeline.select(galvo_run, progress=False, target={"max_error": 0.2})
    return galvo_run, sec


def test_every_family_is_measured_and_bit_exact(galvo_selected):
    run, sec = galvo_selected
    fams = {r["family"] for r in sec["implementations"]}
    assert fams == set(FAMILIES) == {"mlp", "poly", "lut", "hybrid"}
    for r in sec["implementations"]:
        assert r["host"]["bit_exact"] and r["host"]["points"] > 10_000, r["family"]
        for t in ("avr", "pic18", "avr_portable", "pic18_portable"):
            if t == "pic18_portable" and r["family"] == "mlp":
                assert "SDCC" in r["targets"][t]["not_run"]
                continue
            assert r["targets"][t]["bit_exact"], (r["family"], t)
            assert r["targets"][t]["model_hash"] == r["model_hash"]
        for t in ("avr", "pic18"):
            assert r["cycles"][t] > 0 and r["flash_bytes"][t] > 0
    assert sec["check_points"] >= 1001 * 1001


def test_pick_is_the_cheapest_that_meets_the_target(galvo_selected):
    run, sec = galvo_selected
    rows = sec["implementations"]
    picked = [r for r in rows if r["picked"]]
    assert len(picked) == 1
    pick = picked[0]
    assert pick["pre_max"] <= 0.2
    for r in rows:
        if r["pre_max"] <= 0.2:
            assert (pick["cycles"]["avr"], pick["flash_bytes"]["avr"]) <= (r["cycles"]["avr"], r["flash_bytes"]["avr"])
    name = "galvo_cba2012"
    c = (run / "c" / f"{name}.c").read_text()
    assert c == (run / "c" / "alt" / pick["family"] / f"{name}.c").read_text()
    for r in rows:
        assert (run / "c" / "alt" / r["family"] / f"{name}.h").is_file()
    assert f"{name}_ik(const int32_t in_um[" in (run / "c" / f"{name}.h").read_text()
    m = json.loads((run / "metrics.json").read_text())
    assert m["selection"]["pick"]["family"] == pick["family"]


def test_accuracy_is_measured_against_the_exact_ik(galvo_run):
    """The check grid's truth is the analytic IK: a family's pre-rounding error equals a direct
    recomputation at a few grid points."""
    from nnik.implementations.accuracy import accuracy

    problem = pipeline.problem_for(galvo_run)
    impl = FAMILIES["mlp"].fit(problem, FAMILIES["mlp"].ladder(problem)[0])
    acc = accuracy(impl)
    pts, truth = problem.check
    idx = np.random.default_rng(0).choice(len(pts), 500, replace=False)
    direct = np.abs(impl.run(pts[idx]).pre - problem.truth(pts[idx])).max()
    assert direct <= acc["pre_max"] + 1e-12
    assert acc["pre_max"] > 0.0 and acc["points"] == len(pts)


def test_unreachable_error_exits_with_the_best_reached(galvo_run):
    with pytest.raises(NnikError, match=r"no implementation meets max_error 1e-09: the closest is mlp .* at [0-9.]+; try `nnik search`"):
        pipeline.select(galvo_run, progress=False, families=["mlp"], target={"max_error": 1e-9})


def test_cycle_limit_that_nothing_meets(galvo_run):
    require_tool("simavr")
    require_tool("gpsim")
    with pytest.raises(NnikError, match="fits the limits"):
        pipeline.select(galvo_run, progress=False, families=["mlp"], target={"max_error": 100.0, "max_cycles": 10})


@pytest.mark.parametrize("table, msg", [
    ("foo = 1", "[target] foo: unknown key"),
    ('chip = "arm"', "[target] chip: must be one of avr, pic18"),
    ("max_error = 0", "[target] max_error: must be > 0"),
    ("max_error = -0.5", "[target] max_error: must be > 0"),
])
def test_bad_target_table(tmp_path, capsys, table, msg):
    from nnik.cli import main
    from tests.conftest import DATASETS

    text = (DATASETS / "galvo_cba2012.toml").read_text().split("[target]")[0] + f"[target]\n{table}\n"
    p = tmp_path / "s.toml"
    p.write_text(text)
    rc = main(["generate", str(p), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and msg in err[0]


def test_select_command_rejects_a_bad_max_error(galvo_run, capsys):
    from nnik.cli import main

    rc = main(["select", str(galvo_run), "--max-error", "0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--max-error: must be > 0" in err[0]


def test_select_command_names_the_best_error_when_nothing_meets(galvo_run, capsys):
    from nnik.cli import main

    rc = main(["select", str(galvo_run), "--family", "mlp", "--max-error", "1e-9"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "the closest is mlp" in err[0] and "c/alt/" in err[0]
