"""The lut verdict (nnik/report/measured.py): where the lut family's best beats the MLP, the
sentence advises flashing the table only when the table is not already the pick."""

from __future__ import annotations

import copy

from hypothesis import given, strategies as st

from nnik.report.measured import lut_picked, lut_verdicts
from nnik.report.summary import summary_rows

BASE = {
    "unit": "mm", "fixed": {"delivered_max_abs": [0.4, 0.3]},
    "targets": {"avr": {"cycles": 1500, "flash_bytes": 1400}, "pic18": {"not_run": "toolchain missing"}},
    "implementations": [{"family": "poly", "describe": "poly 5", "picked": False},
                        {"family": "lut", "describe": "lut 40x40", "delivered_max_abs": [0.1, 0.1],
                         "targets": {"avr": {"cycles": 900, "flash_bytes": 8200}}}],
    "selection": {"pick": {"family": "lut", "file": "galvo.c"}},
}


def metrics(lut_is_pick: bool) -> dict:
    m = copy.deepcopy(BASE)
    m["implementations"][1]["picked"] = lut_is_pick
    m["implementations"][0]["picked"] = not lut_is_pick
    m["selection"]["pick"]["family"] = "lut" if lut_is_pick else "poly"
    return m


def test_the_table_already_picked_is_not_advised_again():
    wins, _ = lut_verdicts(metrics(True))
    assert len(wins) == 1
    assert "consider flashing the table instead" not in wins[0]
    assert "The table is this machine's pick (c/galvo.c)." in wins[0]
    assert lut_picked(metrics(True))
    row = next(r for r in summary_rows(metrics(True)) if r[0] == "lut family best")
    assert row[1] == "wins, the pick" and "consider flashing" not in row[2]


def test_a_table_not_picked_is_advised():
    wins, _ = lut_verdicts(metrics(False))
    assert len(wins) == 1 and wins[0].endswith("On this machine, consider flashing the table instead.")
    assert not lut_picked(metrics(False))
    row = next(r for r in summary_rows(metrics(False)) if r[0] == "lut family best")
    assert row[1] == "wins"


@given(st.booleans(), st.floats(0.01, 10), st.integers(100, 5000))
def test_advice_iff_the_table_wins_and_is_not_the_pick(picked, lut_err, lut_cycles):
    m = metrics(picked)
    m["implementations"][1]["delivered_max_abs"] = [lut_err, lut_err]
    m["implementations"][1]["targets"]["avr"]["cycles"] = lut_cycles
    wins, losses = lut_verdicts(m)
    beats = lut_cycles < 1500 and lut_err < 0.4
    assert bool(wins) == beats and bool(losses) == (not beats)
    assert any("consider flashing" in w for w in wins) == (beats and not picked)
    assert any("is this machine's pick" in w for w in wins) == (beats and picked)
