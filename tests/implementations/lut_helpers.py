"""Shared by test_lut.py and test_hybrid.py: problems of the shipped scenarios, built once."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from nnik.machine.data import build_dataset
from nnik.implementations.problem import Problem
from nnik.machine.scenario import load_scenario

DATASETS = Path(__file__).resolve().parents[2] / "datasets"


@lru_cache(maxsize=None)
def problem(name: str) -> Problem:
    scn = load_scenario(DATASETS / f"{name}.toml")
    return Problem(scn, build_dataset(scn), unit_um=scn.export["input_unit_um"])


def problem_from(path: Path) -> Problem:
    scn = load_scenario(path)
    return Problem(scn, build_dataset(scn), unit_um=scn.export["input_unit_um"])


def centred_corexy(tmp_path: Path) -> Problem:
    """corexy_nonlinear on a workspace centred on 0: the domain is symmetric, the IK is not."""
    text = (DATASETS / "corexy_nonlinear.toml").read_text()
    text = text.replace("x_mm = [0.0, 200.0]", "x_mm = [-100.0, 100.0]").replace(
        "y_mm = [0.0, 200.0]", "y_mm = [-100.0, 100.0]")
    path = tmp_path / "centred.toml"
    path.write_text(text)
    p = problem_from(path)
    assert np.array_equal(p.lo, -p.hi)
    return p


def host_check(im, tmp_path: Path) -> dict:
    """verify_host of `im` on host_vectors(its problem): its C against its integer model."""
    from nnik.implementations.verify import verify_host

    return verify_host(im, tmp_path / "c", host_vectors(im.problem))


def host_vectors(p: Problem, n: int = 100_000, seed: int = 3) -> np.ndarray:
    """10^5 random in-domain points plus the domain's corners and points outside it."""
    from nnik.implementations.verify import host_vectors as hv

    rng = np.random.default_rng(seed)
    return np.concatenate([rng.integers(p.lo, p.hi + 1, (n, 2)), hv_stub(p, hv)])


def hv_stub(p: Problem, hv) -> np.ndarray:
    class _I:  # host_vectors only reads .problem
        problem = p
    return hv(_I(), n_random=0)


def c_function_body(src: str, name: str) -> str:
    """The portable C function (the #else branch) without comments."""
    import re

    body = src[src.rindex(f"int8_t {name}_ik("):]
    return re.sub(r"/\*.*?\*/", "", body, flags=re.S)
