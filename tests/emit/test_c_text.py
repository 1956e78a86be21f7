"""User text in generated C: comments that cannot be escaped from, and the longest name that
builds on every toolchain."""

from __future__ import annotations

import shutil
import subprocess
import tomllib

import numpy as np
import pytest

from nnik import pipeline
from nnik.emit.c_text import MAX_NAME_LEN, c_comment_safe, c_name_problem
from nnik.machine.scenario import Scenario
from tests.conftest import DATASETS, require_tool
from tests.targets.runner_helpers import need_toolchain

INJECTIONS = [
    "a*/ int injected = 42; /*b/s.toml",
    "x\n#define injected 1\nint injected;",
    "*/*/ int injected; //",
    "caf\u00e9 */ int injected;",
    "/**/int injected;/**/",
]


@pytest.mark.parametrize("text", INJECTIONS)
def test_comment_cannot_be_closed(tmp_path, text):
    """The text inside a block comment compiles to nothing: no symbol, one comment line."""
    require_tool("gcc")
    safe = c_comment_safe(text)
    assert "*/" not in safe and "/*" not in safe and "\n" not in safe and safe.isascii()
    src = tmp_path / "t.c"
    src.write_text(f"/*\n * generated from {safe}\n */\nint keep_me;\n")
    obj = tmp_path / "t.o"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-c", str(src), "-o", str(obj)], check=True)
    syms = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    assert "keep_me" in syms and "injected" not in syms


def test_comment_keeps_ordinary_paths_readable():
    assert c_comment_safe("datasets/galvo_cba2012.toml") == "datasets/galvo_cba2012.toml"


def test_name_rules():
    assert c_name_problem("galvo_cba2012") is None
    assert c_name_problem("g" * MAX_NAME_LEN) is None
    for bad in ("NULL", "nnik_kernel", "NNIK_FLASH", "int8_t", "main", "return", "_x", "9a", "a-b", "g" * (MAX_NAME_LEN + 1)):
        assert c_name_problem(bad), bad


def test_longest_name_builds_on_pic18(tmp_path):
    """Every C file nnik writes for a name of MAX_NAME_LEN characters builds with SDCC/gputils and
    runs on gpsim (one character more made gplink fail with "section must be contiguous")."""
    from nnik.targets import run_on_target

    need_toolchain("pic18")
    raw = tomllib.loads((DATASETS / "galvo_cba2012.toml").read_text())
    raw["name"] = "g" * MAX_NAME_LEN
    raw["dataset"].update(n_test=50)
    raw["training"] = {"adam_steps": 60, "lbfgs_rounds": 3, "restarts": 1}
    scn = Scenario.from_dict(raw, str(tmp_path / "long.toml"), DATASETS)
    out = tmp_path / "out"
    pipeline.generate(scn, out)
    pipeline.train(scn, out, progress=False)
    pipeline.evaluate(out)
    pipeline.export(out)
    sources = sorted((out / pipeline.C_DIR).rglob("*.c"))
    assert len(sources) >= 3
    vec = np.array([[0, 0], [1000, -2000]], dtype=np.int64)
    for src in sources:
        r = run_on_target(target="pic18", sources=[src], include_dirs=[src.parent], name=src.stem, vectors=vec,
                          workdir=tmp_path / "t" / src.parent.name / src.stem, progress=False)
        assert r["outputs"].shape == (2, 2)
    shutil.rmtree(tmp_path / "t")


@pytest.mark.parametrize("kernel", ["fast", "portable"])
@pytest.mark.parametrize("text", INJECTIONS[:2])
def test_mlp_c_keeps_an_injected_path_inside_its_comment(tmp_path, galvo_run, kernel, text):
    """The scenario path goes into the MLP's generated C (both kernels): it must stay a comment."""
    from nnik.emit.templating import write_sources
    from nnik.implementations.mlp.export import render_model_c

    require_tool("gcc")
    model, ds = pipeline.load_pair(galvo_run)
    im = pipeline.quantize_kernel(model, ds, kernel)
    files = render_model_c(im, text)
    write_sources(files, tmp_path)
    obj = tmp_path / "m.o"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-c", str(tmp_path / "galvo_cba2012.c"), "-I", str(tmp_path),
                    "-o", str(obj)], check=True)
    syms = subprocess.run(["nm", str(obj)], capture_output=True, text=True, check=True).stdout
    assert "galvo_cba2012_ik" in syms and "injected" not in syms
