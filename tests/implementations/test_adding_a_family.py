"""Adding a family is one folder and one registry line (docs/families.md: "Adding a family"). A toy family
(tests/implementations/affine/: a least-squares plane per output) is registered with the loader
REGISTRY uses and goes through what every family goes through: the ladder fit and its accuracy
on the check set, the family's best for a target, and the host verification of its C (its int64
C is not meant for the chips, so it is not simulated here)."""

from __future__ import annotations

import pytest

from nnik.implementations import FAMILIES, load_family
from nnik.implementations.verify import verify_host
from nnik.selection import family_bests, fit_ladder
from tests.implementations.lut_helpers import host_vectors, problem

TOY = "tests.implementations.affine.family"


@pytest.fixture
def affine(monkeypatch):
    cls = load_family(TOY)
    monkeypatch.setitem(FAMILIES, cls.family, cls)  # what one line in REGISTRY does for nnik's own
    return cls


def test_a_registered_toy_family_is_fitted_picked_and_verified(affine, tmp_path):
    p = problem("corexy_nonlinear")
    cands = fit_ladder(p, families=["affine"])
    assert [c.config for c in cands] == affine.ladder(p) and all(c.impl is not None for c in cands)
    assert all(c.acc["points"] == len(p.check[0]) and c.acc["pre_max"] > 0 for c in cands)
    # a plane cannot follow a curved IK within a step, so nothing meets a tight target: the
    # family's best is its most accurate configuration; a loose target takes the cheapest
    tight = family_bests(cands, {"chip": "avr", "max_error": 1e-3})["affine"]
    assert tight.acc["pre_max"] == min(c.acc["pre_max"] for c in cands)
    loose = family_bests(cands, {"chip": "avr", "max_error": 1e9})["affine"]
    assert loose.meets(1e9) and loose.est["avr"]["cycles"] == 2000.0
    r = verify_host(tight.impl, tmp_path / "c", host_vectors(p))
    assert r["bit_exact"] and r["mismatches"] == 0 and r["points"] > 100_000
    assert (tmp_path / "c" / f"{p.name}.c").read_text() == tight.impl.render_source()


def test_the_registry_names_every_family_by_its_module():
    from nnik.implementations import REGISTRY

    assert list(REGISTRY) == list(FAMILIES) == ["mlp", "poly", "lut", "hybrid"]
    for name, module in REGISTRY.items():
        assert module == f"nnik.implementations.{name}.family" and load_family(module) is FAMILIES[name]
    with pytest.raises(AttributeError):
        load_family("nnik.implementations.base")  # a module without IMPLEMENTATION is no family


def test_the_search_leaves_a_family_without_knobs_out_and_says_so(affine, tmp_path):
    from nnik.errors import NnikError
    from nnik.search.space import SEARCHED
    from nnik.search.study import search

    assert "affine" not in SEARCHED  # its knobs are not in nnik/search/space.py: `nnik search` skips it
    with pytest.raises(NnikError, match="no knobs in the search space"):
        search(tmp_path, trials=1, families=["affine"], progress=False)
