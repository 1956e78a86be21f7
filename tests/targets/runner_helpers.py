"""Shared helpers of the target-runner tests: toy vectors and their expected outputs."""
from __future__ import annotations

import os

import numpy as np
import pytest

from nnik.targets import available


def need_toolchain(target: str) -> None:
    ok, why = available(target)
    if not ok:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(f"NNIK_REQUIRE_TOOLCHAINS=1 but {why}")
        pytest.skip(why)


def toy_vectors(n_random: int = 90, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    edge = [[0, 0], [1, -1], [-1, 1], [100000, 100000], [-100000, -100000], [100001, 0],
            [0, -100001], [2**31 - 1, -(2**31)], [-(2**31), 2**31 - 1], [-7, -3], [-5, 2]]
    rnd = rng.integers(-150000, 150001, size=(n_random, 2))
    return np.vstack([np.array(edge, dtype=np.int64), rnd])


def toy_reference(vec: np.ndarray):
    a = np.clip(vec[:, 0], -100000, 100000)
    b = np.clip(vec[:, 1], -100000, 100000)
    flags = ((a != vec[:, 0]) | (b != vec[:, 1])).astype(np.int64)
    out = np.stack([(a * 3 + b) >> 2, a - b], axis=1)  # numpy >> on int64 is arithmetic
    return out, flags


def galvo_reference(vec: np.ndarray) -> np.ndarray:
    x = np.clip(vec[:, 0], -250000, 250000) / 1000.0
    y = np.clip(vec[:, 1], -250000, 250000) / 1000.0
    alpha = 0.5 * np.arctan(y / 300.0)
    beta = 0.5 * np.arctan2(np.sqrt(y * y + 300.0 ** 2), x)
    return np.stack([np.round(np.degrees(alpha) / 0.1125), np.round(np.degrees(beta) / 0.1125)], 1)

