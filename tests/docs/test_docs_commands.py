"""Every command the README and docs/*.md show in a ```sh block runs verbatim, in order, from the
root of a fresh copy of the repository, one copy per page (tests/docs/pages.py says how a page
marks its commands).

One step is expensive and many pages begin with it: `nnik run` on a shipped scenario (about a
minute; five or six for the xy_table). SHARED names such steps and what they write; each runs
verbatim in a fresh copy of its own once per session (tests/shared_run.py;
tests/job/test_closed_loop.py shares the xy_table's), and every page whose block holds that exact
command gets that run's output directory copied into its own copy at that point, instead of
training again."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.docs.pages import LANGUAGES, blocks, commands, fresh_copy, pages, shown_failures, shown_nnik_commands
from tests.shared_run import TIMEOUT_S, SessionRuns, shell_env

SHARED = {"nnik run datasets/galvo_cba2012.toml": "build/galvo_cba2012", "nnik run datasets/xy_table.toml": "build/xy_table"}


def run(cmd: str, cwd: Path, page: str, expect: str | None = None) -> None:
    check(subprocess.run(cmd, shell=True, cwd=cwd, env=shell_env(), capture_output=True, text=True, timeout=TIMEOUT_S),
          page, expect)


def check(r: subprocess.CompletedProcess, page: str, expect: str | None = None) -> None:
    cmd = r.args
    if expect is not None:  # a failure the page shows: exit 2 and the page's line, nothing more
        assert (r.returncode, r.stderr.strip()) == (2, expect), f"{page}: `{cmd}`: {r.returncode}, {r.stderr[-800:]}"
        return
    assert r.returncode == 0, f"{page}: `{cmd}` exited {r.returncode}: {(r.stderr or r.stdout)[-800:]}"
    assert "Traceback" not in r.stderr, f"{page}: `{cmd}`: {r.stderr[-800:]}"


@pytest.fixture(scope="session")
def shared_runs(session_runs) -> SessionRuns:
    from nnik.targets import toolchain

    for target in ("avr", "pic18"):
        ok, why = toolchain.available(target)
        if not ok:
            if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
                pytest.fail(why)
            pytest.skip(why)
    assert shutil.which("nnik"), "the nnik console script is installed (pip install -e .)"
    return session_runs


RUNNABLE = [p for p in pages() if commands(p) or shown_failures(p)]


@pytest.mark.parametrize("page", RUNNABLE, ids=lambda p: p.name)
def test_a_pages_commands_run_verbatim_from_a_fresh_copy(page, shared_runs, tmp_path):
    repo = fresh_copy(tmp_path / "nnik")
    for cmd in commands(page):
        if cmd in SHARED:
            out, r = shared_runs.run(cmd, SHARED[cmd])
            check(r, page.name)
            shutil.copytree(out, repo / SHARED[cmd])
        else:
            run(cmd, repo, page.name)
    for cmd, error in shown_failures(page):
        run(cmd, repo, page.name, expect=error)


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.name)
def test_every_nnik_command_a_page_shows_is_run(page):
    ran = set(commands(page))
    assert [c for c in shown_nnik_commands(page) if c not in ran] == []
    assert {lang for lang, _ in blocks(page)} <= LANGUAGES, f"{page.name}: mark each block sh, console, text, ..."


def test_the_docs_have_a_page_per_task_and_the_readme_maps_them():
    names = {p.name for p in pages()}
    for task in ("getting_started", "scenario_reference", "commands", "gcode", "families", "motion", "firmware",
                 "measured_machines"):
        assert f"{task}.md" in names
        assert f"docs/{task}.md" in (pages()[0]).read_text()


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.name)
def test_no_history_on_the_pages(page):
    text = page.read_text().lower()
    for word in ("issue", "session", "not re-run"):
        assert word not in text, f"{page.name} says {word!r}: the pages describe nnik as it is"
