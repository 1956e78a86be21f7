"""`make house`: nnik/ flows one way by the import contracts of pyproject.toml (lint-imports, with
every package under nnik/ on one layer), and no Python file is over 500 lines. The C's one-way
calls: tests/firmware/test_c_calls.py; nnik's module-level circles: tests/test_imports_acyclic.py."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 500


def lint_imports(root: Path) -> subprocess.CompletedProcess:
    """lint-imports on root's pyproject.toml and root/nnik (a dev dependency: `make setup`)."""
    exe = shutil.which("lint-imports")
    assert exe, "lint-imports not found: pip install -e '.[dev]' (make setup)"
    env = dict(os.environ, PYTHONPATH=str(root))
    return subprocess.run([exe, "--no-cache"], cwd=root, env=env, capture_output=True, text=True)


def test_the_import_contracts_hold():
    r = lint_imports(ROOT)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    assert re.search(r"Contracts: [1-9]\d* kept, 0 broken\.", r.stdout), r.stdout[-2000:]


def test_the_contracts_see_an_upward_import_and_a_package_on_no_layer(tmp_path):
    """A copy of nnik/ with machine importing the pipeline (inside a function) and a new top-level
    package: both break the layers contract, each named."""
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    for p in (ROOT / "nnik").rglob("*.py"):
        dst = tmp_path / p.relative_to(ROOT)
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(p, dst)
    data = tmp_path / "nnik" / "machine" / "data.py"
    data.write_text(data.read_text() + "\n\ndef _upward():\n    from nnik import pipeline\n\n    return pipeline\n")
    (tmp_path / "nnik" / "attic").mkdir()
    (tmp_path / "nnik" / "attic" / "__init__.py").write_text("")
    r = lint_imports(tmp_path)
    assert r.returncode != 0
    assert "nnik.machine.data -> nnik.pipeline" in r.stdout, r.stdout[-3000:]
    assert "nnik.attic" in r.stdout, r.stdout[-3000:]


def test_no_python_file_is_over_500_lines():
    long = {str(p.relative_to(ROOT)): n for top in ("nnik", "tests", "scripts") for p in (ROOT / top).rglob("*.py")
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, long


def test_no_two_test_modules_share_a_name():
    """pytest imports a test folder without __init__.py by the file's basename: two test_x.py in two
    folders stop the whole run at collection ("import file mismatch")."""
    seen: dict[str, Path] = {}
    for p in sorted((ROOT / "tests").rglob("*.py")):
        if p.name in ("__init__.py", "conftest.py") or (p.parent / "__init__.py").is_file():
            continue
        assert p.name not in seen, f"{p.relative_to(ROOT)} and {seen[p.name].relative_to(ROOT)}: rename one"
        seen[p.name] = p
