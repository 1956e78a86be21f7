"""Static cost model of the `poly` family (placeholder until calibrated)."""
from __future__ import annotations


def estimate(impl, target: str) -> dict:
    raise NotImplementedError
