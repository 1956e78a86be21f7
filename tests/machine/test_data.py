from __future__ import annotations

import numpy as np
import pytest

from nnik.machine.data import Dataset, build_dataset, sample_points
from nnik.machine.kinematics import Workspace
from nnik.machine.scenario import load_scenario
from tests.conftest import DATASETS

WS = Workspace((-10.0, 30.0), (5.0, 6.0))


@pytest.mark.parametrize("method", ["sobol", "uniform", "grid"])
def test_sampling_is_deterministic_and_inside(method):
    a = sample_points(WS, 500, method, 3)
    b = sample_points(WS, 500, method, 3)
    np.testing.assert_array_equal(a, b)
    assert len(a) >= 500
    assert np.all(a >= WS.lo) and np.all(a <= WS.hi)
    if method != "grid":
        assert not np.array_equal(a, sample_points(WS, 500, method, 4))


def test_dataset_labels_are_exact_ik_and_roundtrip(tmp_path):
    scn = load_scenario(DATASETS / "galvo_cba2012.toml")
    ds = build_dataset(scn)
    assert len(ds.p["train"]) == 1000 and len(ds.p["test"]) >= 20000
    m = scn.mechanism
    q_rad = m.q_rest + scn.actuator.from_units(ds.q["test"])
    assert np.abs(m.forward(q_rad) - ds.p["test"]).max() < 1e-9
    # 3200 microsteps per revolution: 0.1125 deg per microstep
    assert scn.actuator.units_per_rad == pytest.approx(3200 / (2 * np.pi))
    ds.save(tmp_path / "d.npz")
    back = Dataset.load(tmp_path / "d.npz")
    for s in ("train", "val", "test"):
        np.testing.assert_array_equal(back.p[s], ds.p[s])
        np.testing.assert_array_equal(back.q[s], ds.q[s])
    assert back.meta["unit"] == "microstep"


def test_measured_split_holds_out_rows():
    scn = load_scenario(DATASETS / "corexy_measured.toml")
    ds = build_dataset(scn)
    rows = {tuple(r) for r in ds.p["train"]}
    assert not any(tuple(r) in rows for r in ds.p["test"])
    assert sum(len(v) for v in ds.p.values()) == 600
