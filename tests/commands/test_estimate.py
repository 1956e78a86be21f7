"""`nnik estimate --json`: the cost model's prediction as one JSON object, the figures the
console line shows."""

from __future__ import annotations

import json

from nnik.cli import main
from tests.bad_input import tiny_run  # noqa: F401 (fixture)


def test_estimate_json_is_the_printed_prediction(tiny_run, capsys):  # noqa: F811
    capsys.readouterr()
    assert main(["estimate", str(tiny_run), "--target", "avr"]) == 0
    line = capsys.readouterr().out
    assert main(["estimate", str(tiny_run), "--target", "avr", "--json"]) == 0
    out = capsys.readouterr().out
    e = json.loads(out)  # stdout holds the object and nothing else
    assert e["target"] == "avr"
    assert f"{e['cycles']:.0f} cycles" in line and f"flash {e['flash_bytes']} B, RAM {e['ram_bytes']} B" in line
