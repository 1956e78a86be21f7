"""The honest comparison (nnik.job.servo_compare) on a short job: every controller on every plant,
the nominal figures the same as the closed-loop job's own loop and measure, the drift and the
differing plant really different, the diverged flag by its stated rule, the table and the learning
curves written."""

from __future__ import annotations

import json

import pytest

from nnik.dynamics.servo.closed_loop import simulate
from nnik.implementations.servo import make
from nnik.implementations.servo.nn.pretrain import pretrain
from nnik.implementations.servo.tune import tune
from nnik.job.parse import JobRequest
from nnik.job.reference import job_reference
from nnik.job.servo_compare import METRICS, PLANTS, compare, diverged
from nnik.job.servo_measure import measure
from nnik.machine.scenario import load_scenario
from tests.conftest import DATASETS
from tests.implementations.servo.paths import plant_models

JOB = "G21 G90\nG4 P0.1\n;@step X3 Y1\nG4 P0.4\nG1 X8 Y4 F600\nG1 X8 Y8\nG4 P0.3\n"


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cmp")
    scn = load_scenario(DATASETS / "xy_table.toml")
    job = tmp / "short.gcode"
    job.write_text(JOB)
    _, ref = job_reference(JobRequest(job, scn))
    models = plant_models(scn.servo)
    gains = {k: tune(k, scn.servo, models, ref.counts, 4, 1) for k in ("pid", "ccc")}
    gains["nn_vector"], _ = pretrain("nn_vector", scn.servo, models, (0.0, 0.0), 1, 1, [("short", ref.counts)])
    out = compare(scn, gains, tmp / "out", say=lambda s: None, jobs=[job], models=models)
    return scn, ref, gains, out, tmp / "out"


def test_every_controller_on_every_plant(compared):
    scn, ref, gains, out, d = compared
    res = out["results"]["short.gcode"]
    assert list(res) == list(PLANTS)
    for plant in PLANTS:
        assert list(res[plant]) == ["pid", "ccc", "nn_vector"]
        for kind, r in res[plant].items():
            assert r["contour_max_um"] >= r["contour_rms_um"] >= 0 and r["tracking_rms_um"] >= 0
            assert (r["updates"] > 0) == (kind == "nn_vector")
    # the nominal plant is the closed-loop job's own loop and measure
    for kind in ("pid", "nn_vector"):
        fig, _ = measure(ref, simulate(scn.servo, make(kind, gains[kind], scn.servo), ref.counts))
        assert res["nominal"][kind]["contour_rms_um"] == fig["contour_um"]["rms_um"]
        assert res["nominal"][kind]["contour_max_um"] == fig["contour_um"]["max_um"]
    for plant in ("drift", "differing"):
        assert res[plant]["pid"]["contour_rms_um"] != res["nominal"]["pid"]["contour_rms_um"]


def test_the_table_the_json_and_the_learning_curves(compared):
    _, _, _, out, d = compared
    md = (d / "compare.md").read_text()
    for plant in PLANTS:  # one row per controller in the job's table, one in the headline
        assert all(md.count(f"| {plant} | {k} |") == 1 for k in ("pid", "ccc", "nn_vector"))
        assert md.count(f"| short.gcode | {plant} |") == 1
    assert json.loads((d / "compare.json").read_text())["headline"] == out["headline"]
    assert out["figures"] == [str(d / "learning_short_nn_vector.png")]
    assert "| X | " in md and "| 1.0103 |" in md and "| 0.6047 |" in md  # ours beside the seed's
    assert (d / "learning_short_nn_vector.png").stat().st_size > 10_000
    for h in out["headline"]:
        row = out["results"][h["job"]][h["plant"]]
        assert h["best_rms_um"] == min(r["contour_rms_um"] for r in row.values())
        for key, tag in METRICS:
            (bk, b), (nk, n) = h[f"baseline_{tag}"], h[f"neural_{tag}"]
            assert h[f"baseline_wins_{tag}"] == ("yes" if b < n else "no" if n < b else "tie")
            assert nk == "nn_vector" and b == min(row[k][key] for k in ("pid", "ccc")) == row[bk][key]


def test_the_diverged_rule():
    pid = {"contour_max_um": 10.0}
    ok = {"clamp_share": 0.01, "contour_max_um": 100.0}
    assert diverged(ok, pid, 2.5) is None
    assert diverged({**ok, "clamp_share": 0.0101}, pid, 2.5) == "clamps"
    assert diverged({**ok, "contour_max_um": 100.01}, pid, 2.5) == "10x pid"
    assert diverged({**ok, "contour_max_um": 24.0}, {"contour_max_um": 0.0}, 2.5) is None  # the floor: a count
    assert diverged({**ok, "contour_max_um": 26.0}, {"contour_max_um": 0.0}, 2.5) == "10x pid"
