"""Shared fixtures: the shipped scenarios, run once per session through the real pipeline (or, for
session_runs, through the command line)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

from nnik import pipeline
from nnik.machine.scenario import load_scenario
from tests.shared_build import built_once
from tests.shared_run import SessionRuns

# `make test` draws the same examples on every run and every machine (derandomize: a seed from each
# test's own code), so what passed here is what CI runs; no deadline and no too-slow check, since
# the tests share the cores. `make bench` draws fresh random examples (NNIK_HYPOTHESIS_PROFILE=explore).
settings.register_profile("nnik", derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("explore", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("NNIK_HYPOTHESIS_PROFILE", "nnik"))

ROOT = Path(__file__).resolve().parents[1]
DATASETS = ROOT / "datasets"


def _scenario_file(name: str, outdir: Path) -> Path:
    """The shipped scenario, or with NNIK_TEST_SEED_OFFSET=k a copy whose [dataset] seed is moved by
    k: the same machine with another sampling and training, as another machine's CPU would train
    it. `make bench` runs the model-dependent tests that way too, so no assertion can
    lean on one trained model's figures."""
    src = DATASETS / f"{name}.toml"
    shift = int(os.environ.get("NNIK_TEST_SEED_OFFSET", "0"))
    if not shift:
        return src
    text, n = re.subn(r"(?m)^(seed\s*=\s*)(\d+)", lambda m: f"{m.group(1)}{int(m.group(2)) + shift}", src.read_text())
    if not n:  # the default seed is 0
        text, n = re.subn(r"(?m)^\[dataset\]$", f"[dataset]\nseed = {shift}", text)
    assert n == 1, f"{src}: expected one [dataset] seed"
    dst = outdir / f"{name}.toml"
    dst.write_text(text)
    return dst


def _run(name: str, outdir: Path) -> None:
    scn = load_scenario(_scenario_file(name, outdir))
    pipeline.generate(scn, outdir)
    pipeline.train(scn, outdir, progress=False)
    pipeline.evaluate(outdir)


@pytest.fixture(scope="session")
def galvo_run(tmp_path_factory) -> Path:
    """build dir of datasets/galvo_cba2012.toml after generate/train/evaluate."""
    return built_once(tmp_path_factory, "galvo_cba2012", lambda d: _run("galvo_cba2012", d))[0]


@pytest.fixture(scope="session")
def corexy_run(tmp_path_factory) -> Path:
    """build dir of datasets/corexy_nonlinear.toml (residual mode) after generate/train/evaluate."""
    return built_once(tmp_path_factory, "corexy_nonlinear", lambda d: _run("corexy_nonlinear", d))[0]


@pytest.fixture(scope="session")
def session_runs(tmp_path_factory):
    """A long shell command (`nnik run datasets/xy_table.toml`) run once per session for every test
    that needs its output (tests/shared_run.py)."""
    return SessionRuns(tmp_path_factory)


def write_toml(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def require_tool(tool: str) -> None:
    """Skip when a toolchain binary is missing, unless NNIK_REQUIRE_TOOLCHAINS=1 (CI), where it fails."""
    import os
    import shutil

    if shutil.which(tool) is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(f"{tool} not found but NNIK_REQUIRE_TOOLCHAINS=1")
        pytest.skip(f"{tool} not installed (run `make toolchains`)")


@pytest.fixture(scope="session")
def galvo_fixed(galvo_run) -> dict:
    """galvo_cba2012 exported to C and verified on the host; returns metrics.json."""
    pipeline.verify(galvo_run, "host")
    return pipeline.load_metrics(galvo_run)


@pytest.fixture(scope="session")
def corexy_fixed(corexy_run) -> dict:
    pipeline.verify(corexy_run, "host")
    return pipeline.load_metrics(corexy_run)
