"""The model's own flash on both chips, from the linker map (issue 11, section 1): runtime helpers
the model pulls in count, and the figure agrees with a second, independent reading of the maps."""

from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest

from nnik.emit.templating import write_sources
from nnik.implementations import family
from nnik.targets.pic18 import parse_map
from nnik.targets.pic18_sizes import parse_detail
from tests.implementations.lut_helpers import problem
from tests.targets.runner_helpers import need_toolchain


@pytest.fixture(scope="module")
def lut_c(tmp_path_factory):
    """A galvo table of the lut family with int32 entries: its portable C multiplies 32-bit values,
    so it needs runtime helpers."""
    d = tmp_path_factory.mktemp("lut")
    p = problem("galvo_cba2012")
    cls = family("lut")
    write_sources(cls.fit(p, {**cls.ladder(p)[0], "bits": 32}).render_c(), d)
    return d / "galvo_cba2012.c"


def _run(target, src, workdir):
    from nnik.targets import run_on_target

    return run_on_target(target=target, sources=[src], include_dirs=[src.parent], name=src.stem,
                         vectors=np.array([[0, 0], [1000, -2000]]), workdir=workdir, progress=False,
                         extra_cflags=["-DNNIK_PORTABLE"])


def test_pic18_counts_runtime_helpers(lut_c, tmp_path):
    need_toolchain("pic18")
    r = _run("pic18", lut_c, tmp_path)
    assert "long_mullong.asm" in r["model_runtime"], r["model_runtime"]
    # a second reading: whole program with the model call, minus the program without it, minus
    # what the call itself added to main()
    wd = tmp_path / "pic18"
    own, none = (wd / "size_own" / "prog.map").read_text(), (wd / "size_none" / "prog.map").read_text()
    main_size = [{s.name: s.size for s in parse_detail(m)[0]}["S_nnik_size_main__main"] for m in (own, none)]
    assert r["model_flash_bytes"] == parse_map(own)[1] - parse_map(none)[1] - (main_size[0] - main_size[1])
    # the harness-minus-stub figure nets out helpers the stub uses too
    assert r["model_flash_bytes"] > r["stub_delta_flash_bytes"]


def _avr_text_data(elf):
    out = subprocess.run(["avr-size", "-A", str(elf)], capture_output=True, text=True, check=True).stdout
    sec = {p[0]: int(p[1]) for p in (ln.split() for ln in out.splitlines()) if len(p) >= 3 and p[1].isdigit()}
    return sec.get(".text", 0) + sec.get(".data", 0)


def _avr_main_size(elf):
    out = subprocess.run(["avr-nm", "-S", str(elf)], capture_output=True, text=True, check=True).stdout
    m = re.search(r"^[0-9a-f]+ ([0-9a-f]+) T main$", out, re.MULTILINE)
    return int(m.group(1), 16)


def test_avr_counts_runtime_helpers(lut_c, tmp_path):
    need_toolchain("avr")
    r = _run("avr", lut_c, tmp_path)
    assert any("mul" in f for f in r["model_runtime"]), r["model_runtime"]
    wd = tmp_path / "avr-Os"
    own, none = wd / "size_own" / "prog.elf", wd / "size_none" / "prog.elf"
    expect = _avr_text_data(own) - _avr_text_data(none) - (_avr_main_size(own) - _avr_main_size(none))
    assert abs(r["model_flash_bytes"] - expect) <= 2, (r["model_flash_bytes"], expect)  # alignment fill
