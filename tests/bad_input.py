"""Shared checks for the bad-input tests: exit code 2, one stderr line naming the problem, and
the output directory exactly as it was."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import pytest

from nnik.cli import main
from tests.conftest import DATASETS
from tests.shared_build import built_once

GALVO = (DATASETS / "galvo_cba2012.toml").read_text()
COREXY = (DATASETS / "corexy_nonlinear.toml").read_text()
MEASURED = (DATASETS / "corexy_measured.toml").read_text()
TINY_TRAINING = "[training]\nadam_steps = 60\nlbfgs_rounds = 3\nrestarts = 1\n"


def snapshot(d: Path) -> dict:
    """{relative path: sha256 or 'dir'} of everything under d ({} if d does not exist)."""
    d = Path(d)
    if not d.exists():
        return {}
    if d.is_file():
        return {".": hashlib.sha256(d.read_bytes()).hexdigest()}
    out = {}
    for p in sorted(d.rglob("*")):
        out[str(p.relative_to(d))] = "dir" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def fails(capsys, argv: list[str], *needles: str, watch: Path | None = None) -> str:
    """Run `nnik argv` in-process; assert exit 2, a single `nnik: error:` line holding every
    needle, no traceback, and (if given) the directory `watch` unchanged. Returns the line."""
    before = snapshot(watch) if watch is not None else None
    capsys.readouterr()
    rc = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("nnik: error: "), lines[0]
    for n in needles:
        assert n in lines[0], (n, lines[0])
    if watch is not None:
        assert snapshot(watch) == before, f"{watch} changed"
    return lines[0]


def with_training(text: str, training: str = TINY_TRAINING) -> str:
    """The scenario text with its [training] table replaced by `training`."""
    head = text.split("[training]")[0]
    return head + training


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory) -> Path:
    """A galvo run with a tiny training budget: generate, train, evaluate and export through the CLI.
    Tests copy it (`copy_run`) before spoiling anything."""
    def build(d: Path) -> None:
        toml = d / "tiny.toml"
        toml.write_text(with_training(GALVO.replace("n_test = 20000", "n_test = 300")))
        out = d / "out"
        for argv in (["generate", toml, "-o", out], ["train", toml, "-o", out], ["evaluate", out], ["export", out]):
            assert main([str(a) for a in argv]) == 0, argv

    return built_once(tmp_path_factory, "tiny_run", build)[0] / "out"


def copy_run(run: Path, dest: Path) -> Path:
    shutil.copytree(run, dest)
    return dest
