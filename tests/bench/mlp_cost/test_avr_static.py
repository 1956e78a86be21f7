"""nnik.bench.mlp_cost.avr_static: the cycles counted from avr-gcc's disassembly of a two-layer
fast-kernel network (C path, output folded: straight-line code at -O2; -Os rolls the constant
shifts into loops) are what simavr measures."""

from __future__ import annotations

import pytest

from nnik.bench.mlp_cost import search_check as sc
from nnik.bench.mlp_cost.avr_static import static_cycles
from nnik.implementations.mlp.cost.fast_features import fast_path
from nnik.implementations.mlp.cost.synthetic import CalSpec, synthetic_model


@pytest.fixture()
def avr():
    from nnik.targets import available

    ok, why = available("avr")
    if not ok:
        pytest.skip(why)


@pytest.mark.parametrize("hidden,seed", [((6, 6), 1), ((3, 8), 5)])
def test_static_count_of_the_two_layer_c_path_is_the_measured_count(avr, tmp_path, hidden, seed):
    sp = CalSpec("galvo", hidden, tanh="", weight_bits=16, seed=seed, gain=0.6)
    im = synthetic_model(sp, kernel=sc.KERNEL)
    assert fast_path(im, "avr") == "c" and 15 + int(im.out.g) - int(im.out.F) == 0  # no output loop
    rows = sc.check([sp], ["avr-gcc-O2"], n_vec=12, workdir=tmp_path, verbose=False)
    for r in rows:
        obj = next((tmp_path / sp.label.replace(":", "_") / r["profile"]).glob("**/model0_*.o"))
        total, parts = static_cycles(obj)
        assert parts and total > 0
        assert abs(total - r["cycles_meas"]) <= 0.01 * r["cycles_meas"], (r["profile"], total, r["cycles_meas"])
