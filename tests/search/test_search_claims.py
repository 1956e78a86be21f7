"""A measured machine in `nnik search` (issue 15): the max_error constraint and the objective are
the claimed max (its reference's error included), not the error against the reference."""

from __future__ import annotations

import pytest

from nnik.search import study as search


def test_the_constraint_is_the_claim_where_there_is_one():
    target = {"max_error": 0.5}
    exact = {"pre_max": 0.4, "cycles": 500.0, "flash_bytes": 900}
    measured = {**exact, "claimed_max": 0.62}
    assert search.constraint_values(exact, target)["max_error"] == pytest.approx(-0.1)
    assert search.constraint_values(measured, target)["max_error"] == pytest.approx(0.12)
    assert search.feasible(exact, target) and not search.feasible(measured, target)
    assert search.feasible(measured, {"max_error": 0.62})


def test_the_wide_polynomial_is_in_the_search_space():
    from nnik.implementations.poly.family import PolyImpl
    from nnik.search.space import config_of, params_of
    from tests.implementations.lut_helpers import problem

    p = problem("galvo_cba2012")
    for cfg in PolyImpl.ladder(p):  # every ladder rung, 16 and 32 bits, is expressible
        params = params_of("poly", cfg)
        assert params is not None and params["poly_width"] == cfg.get("width", 16)
        full = {"poly_coef_bits": 16, "poly_split": "none", "poly_lsb": False, "poly_rounding": True, **params}
        assert config_of("poly", full, p) == cfg
