"""The README's front door: the block of commands a user types after `make demo` runs verbatim,
from the root of a fresh copy of the repository, with the relative paths exactly as printed."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

FENCE = re.compile(r"```readme-commands\n(.*?)```", re.S)


def readme_commands() -> list[str]:
    blocks = FENCE.findall((ROOT / "README.md").read_text())
    assert len(blocks) == 1, "the README has one ```readme-commands block"
    cmds = [ln.strip() for ln in blocks[0].splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    assert cmds and all(c.startswith("nnik ") for c in cmds)
    return cmds


DOCS_FENCE = re.compile(r"```docs-commands\n(.*?)```", re.S)


def docs_commands() -> list[tuple[str, str]]:
    """(page, command) of every ```docs-commands block in docs/*.md: run after the README's."""
    out = []
    for page in sorted((ROOT / "docs").glob("*.md")):
        for block in DOCS_FENCE.findall(page.read_text()):
            out += [(page.name, ln.strip()) for ln in block.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    return out


def fresh_copy(dst: Path) -> Path:
    """The tracked files of the repository (what a clone has), without build/ or caches."""
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for rel in filter(None, files.decode().split("\0")):
        src = ROOT / rel
        if src.is_file():
            (dst / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst / rel)
    return dst


def test_readme_commands_run_verbatim_from_a_fresh_copy(tmp_path):
    from nnik.targets import toolchain

    for target in ("avr", "pic18"):
        ok, why = toolchain.available(target)
        if not ok:
            if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
                pytest.fail(why)
            pytest.skip(why)
    repo = fresh_copy(tmp_path / "nnik")
    nnik = shutil.which("nnik")
    assert nnik, "the nnik console script is installed (pip install -e .)"
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    for page, cmd in [("README.md", c) for c in readme_commands()] + docs_commands():
        r = subprocess.run(cmd, shell=True, cwd=repo, env=env, capture_output=True, text=True, timeout=1200)
        assert r.returncode == 0, f"{page}: `{cmd}` exited {r.returncode}: {(r.stderr or r.stdout)[-800:]}"
        assert "Traceback" not in r.stderr, cmd
    out = repo / "build" / "galvo_cba2012"
    assert (out / "c" / "galvo_cba2012.c").is_file() and (out / "report" / "index.html").is_file()
    assert (repo / "build" / "galvo_cba2012_arduino" / "library.properties").is_file()


@pytest.mark.parametrize("cmd", ["make demo", "make test"])
def test_the_two_commands_are_in_the_readme_and_the_makefile(cmd):
    readme = (ROOT / "README.md").read_text()
    assert f"\n{cmd} " in readme
    assert re.search(rf"(?m)^{cmd.split()[1]}:", (ROOT / "Makefile").read_text())
    assert "make test" in (ROOT / ".ci" / "run").read_text()
