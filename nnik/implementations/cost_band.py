"""The cycle band a family's cost model states: the one its recorded check measured.

``python3 -m nnik.bench.costs --record`` measures every family's estimates against simavr and
gpsim (shipped scenarios and random machines, configurations drawn as `nnik search` draws them)
and stores, per target, the worst |error| rounded up to 0.1 % in the family's calibration file
(``check.targets.<target>.band_pct``).  An estimate states that band (None: no check recorded
for the target)."""

from __future__ import annotations

GOAL_PCT = 3.0


def stated_band(cal: dict | None, target: str) -> float | None:
    t = ((cal or {}).get("check") or {}).get("targets", {}).get(target)
    return None if t is None else float(t["band_pct"])
