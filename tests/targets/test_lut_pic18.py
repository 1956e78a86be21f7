"""The LUT baseline is bit-exact on the PIC18 (SDCC 4.2 miscompiles some 32-bit shifts by 15-19;
the table's index mapping and rounding used to be off by one step in most calls)."""

from __future__ import annotations

import numpy as np
import pytest

from nnik.implementations.lut import baseline as lut_baseline
from nnik.machine.data import build_dataset
from nnik.emit.templating import write_sources
from nnik.machine.scenario import load_scenario
from tests.conftest import DATASETS
from tests.targets.runner_helpers import need_toolchain


@pytest.mark.parametrize("name,budget", [("corexy_measured", 100), ("galvo_cba2012", 572)])
def test_lut_bit_exact_on_gpsim(tmp_path, name, budget):
    from nnik.targets import run_on_target

    need_toolchain("pic18")
    scn = load_scenario(DATASETS / f"{name}.toml")
    ds = build_dataset(scn)
    lut = lut_baseline.build_lut(scn, budget, ds.p["train"], ds.q["train"])
    write_sources(lut_baseline.render_lut_c(lut), tmp_path)
    rng = np.random.default_rng(1)
    span = np.array(lut.hi_um) - np.array(lut.lo_um)
    vec = np.concatenate([np.rint(ds.p["test"][:200] * 1000),
                          rng.uniform(np.array(lut.lo_um) - span / 4, np.array(lut.hi_um) + span / 4, (56, 2))])
    vec = vec.astype(np.int64)
    want, flags, _ = lut_baseline.lut_int(lut, vec)
    r = run_on_target(target="pic18", sources=[tmp_path / f"{name}_lut.c"], include_dirs=[tmp_path],
                      name=f"{name}_lut", vectors=vec, workdir=tmp_path / "t", progress=False)
    bad = np.any(r["outputs"] != want, axis=1) | (r["flags"] != flags)
    assert int(bad.sum()) == 0, (int(bad.sum()), vec[bad][:3], r["outputs"][bad][:3], want[bad][:3])
    assert flags.any() and not flags.all()  # both clamped and in-domain calls were run
