"""A session fixture's build done once per test run, whether pytest runs alone or with xdist's
workers (scripts/run_tests.sh runs two, one a core).

`built_once(tmp_path_factory, name, build)`: alone, `build(dir)` runs in a fresh temporary
directory, as before. Under xdist, the first worker to ask builds into a directory beside the
workers' own, under a file lock, and marks it done; every worker then gets its own copy, so a test
or fixture that writes into its build (an export, a verify) never races another worker's."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Callable

from filelock import FileLock


def built_once(tmp_path_factory, name: str, build: Callable[[Path], dict | None]) -> tuple[Path, dict]:
    """(the caller's own directory, what build returned: a small JSON-able dict or None)."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        d = tmp_path_factory.mktemp(name)
        return d, build(d) or {}
    root = tmp_path_factory.getbasetemp().parent / "built_once"
    root.mkdir(exist_ok=True)
    src, done = root / name, root / f"{name}.json"
    with FileLock(str(root / f"{name}.lock")):
        if not done.exists():
            if src.exists():  # a worker that failed half-way
                shutil.rmtree(src)
            src.mkdir()
            info = build(src) or {}
            done.write_text(json.dumps(info))
    dst = tmp_path_factory.mktemp(name)
    shutil.copytree(src, dst, dirs_exist_ok=True, symlinks=True)
    return dst, json.loads(done.read_text())
