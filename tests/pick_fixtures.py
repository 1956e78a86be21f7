"""A small galvo run that ends with a finished, verified pick (`nnik run` on a tiny training
budget, target 0.1 microstep: every family reaches it in a few rungs), for the tests of what
gets delivered (pick.json, nnik verify, job, export --arduino)."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import pytest

from nnik.files import pick_state
from nnik.cli import main
from tests.bad_input import GALVO, TINY_TRAINING
from tests.conftest import require_tool
from tests.shared_build import built_once

TINY_TARGET = 0.1


def tiny_pick_toml(max_error: float = TINY_TARGET) -> str:
    body = GALVO.split("[training]")[0].replace("n_test = 20000", "n_test = 300").replace("hidden = [6]", "hidden = [3]")
    return body + TINY_TRAINING + f'\n[target]\nchip = "avr"\nmax_error = {max_error}\n'


RUN_SECONDS: dict = {}  # how long the fixture's uninterrupted `nnik run` took (kill delays are drawn from it)


@pytest.fixture(scope="session")
def picked_run(tmp_path_factory) -> Path:
    """OUTDIR of a finished `nnik run` of the tiny galvo (pick.json written and its C verified).
    Tests copy it (`copy_picked`) before changing anything."""
    for tool in ("gcc", "avr-gcc", "simavr", "gpsim"):
        require_tool(tool)
    from nnik.targets import available

    ok, why = available("pic18")  # SDCC's pic16 port lives in nnik's own toolchain directory
    if not ok:
        pytest.skip(why)
    def build(d: Path) -> dict:
        toml = d / "tiny.toml"
        toml.write_text(tiny_pick_toml())
        t0 = time.perf_counter()
        assert main(["run", str(toml), "-o", str(d / "out")]) == 0
        return {"run": time.perf_counter() - t0}

    d, seconds = built_once(tmp_path_factory, "picked", build)
    RUN_SECONDS.update(seconds)
    out = d / "out"
    st = pick_state.status(out)
    assert st.ok, st.message
    return out


def copy_picked(run: Path, dest: Path) -> Path:
    shutil.copytree(run, dest, ignore=shutil.ignore_patterns("report", "job", "targets"))
    return dest
