"""The README's front door: the two commands of a fresh clone are in the README and the Makefile,
and the commands a user types next are a ```sh block, which tests/docs/test_docs_commands.py runs
verbatim in a fresh copy of the repository, as it runs every page's."""

from __future__ import annotations

import re

import pytest

from tests.conftest import ROOT
from tests.docs.pages import commands

README_MAX_LINES = 250


@pytest.mark.parametrize("cmd", ["make demo", "make test"])
def test_the_two_commands_are_in_the_readme_and_the_makefile(cmd):
    readme = (ROOT / "README.md").read_text()
    assert f"\n{cmd} " in readme
    assert re.search(rf"(?m)^{cmd.split()[1]}:", (ROOT / "Makefile").read_text())
    assert "make test" in (ROOT / ".ci" / "run").read_text()


def test_the_readme_is_one_page_with_the_next_commands():
    readme = ROOT / "README.md"
    assert len(readme.read_text().splitlines()) <= README_MAX_LINES
    cmds = commands(readme)
    assert len(cmds) >= 5 and all(c.startswith("nnik ") for c in cmds)
    assert cmds[0] == "nnik run datasets/galvo_cba2012.toml"
