"""docs/closed_loop.md's identification example is what the commands print: `nnik excite` and
`nnik identify` on the shipped scenario, run as the page shows them, give the page's text blocks
line for line (so the figures the page quotes are measured, and stay so)."""

from __future__ import annotations

import re

from tests.commands.test_identify import nnik
from tests.conftest import ROOT


def example_blocks() -> list[str]:
    page = (ROOT / "docs" / "closed_loop.md").read_text()
    section = page.split("### Example: the shipped scenario", 1)[1].split("\n### ", 1)[0]
    return re.findall(r"```text\n(.*?)```", section, re.S)


def test_the_pages_example_is_what_the_commands_print(tmp_path):
    excite_text, identify_text = example_blocks()
    r = nnik("excite", ROOT / "datasets" / "xy_table.toml", "-o", "xy_excite", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout == excite_text
    r = nnik("identify", "xy_excite/log.csv", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout == identify_text
