"""A shell command that writes an output directory and takes minutes (`nnik run
datasets/xy_table.toml`: five or six), run once per test session for every test that needs it: the
docs' pages that show it (tests/docs/test_docs_commands.py) and the tests of what it writes
(tests/job/test_closed_loop.py).

`SessionRuns.run(cmd, outdir)` (the session fixture `session_runs`, tests/conftest.py) runs `cmd`
verbatim in a shell from the root of a fresh copy of the repository, as a page's ```sh line runs,
and returns (its output directory `outdir`, moved out of the copy; the command's CompletedProcess).
Under xdist one worker runs it for all of them and each worker gets its own copy
(tests/shared_build.py); alone, it runs once and is kept. The command's failure is returned, not
raised, so that it runs once even then: each caller asserts on the CompletedProcess. A caller that
writes into the output directory copies it first."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from tests.shared_build import built_once

TIMEOUT_S = 1200


def shell_env() -> dict:
    """The environment a page's command runs in: `nnik` is this interpreter's console script."""
    return {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}


def _build(cmd: str, outdir: str, d: Path) -> dict:
    from tests.docs.pages import fresh_copy  # not at the top: tests/docs/pages.py imports tests/conftest.py

    repo = fresh_copy(d / "repo")
    r = subprocess.run(cmd, shell=True, cwd=repo, env=shell_env(), capture_output=True, text=True, timeout=TIMEOUT_S)
    if (repo / outdir).is_dir():
        shutil.move(repo / outdir, d / "out")
    shutil.rmtree(repo)
    return {"returncode": r.returncode, "stdout": r.stdout, "stderr": r.stderr}


class SessionRuns:
    def __init__(self, tmp_path_factory):
        self.factory, self.done = tmp_path_factory, {}

    def run(self, cmd: str, outdir: str) -> tuple[Path, subprocess.CompletedProcess]:
        """(the output directory, read only; the CompletedProcess of `cmd`, args the command line)."""
        if cmd not in self.done:
            name = re.sub(r"\W+", "_", cmd)
            d, info = built_once(self.factory, name, lambda d: _build(cmd, outdir, d))
            self.done[cmd] = d / "out", subprocess.CompletedProcess(cmd, **info)
        return self.done[cmd]
