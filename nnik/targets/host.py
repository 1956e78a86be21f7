"""The host build: compile generated C with sanitizers and run it with a driver (each family's
verification compares the outputs with its integer model)."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.emit.templating import CODEGEN

HOST_FLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O1",
              "-fsanitize=undefined,address", "-fno-sanitize-recover=all"]


def build_and_run(c_dir: Path, prefix: str, driver: str, defines: list[str], in_um: np.ndarray,
                   libs: tuple[str, ...] = (), cc: str = "gcc") -> str:
    """Compile PREFIX.c with a host driver (sanitized), feed it "x y" lines, return its stdout."""
    if shutil.which(cc) is None:
        raise NnikError(f"host C compiler {cc!r} not found")
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "drv"
        cmd = [cc, *HOST_FLAGS, *defines, "-I", str(c_dir), str(CODEGEN / "harness" / "host" / driver),
               str(c_dir / f"{prefix}.c"), "-o", str(exe), *libs]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            first = r.stderr.strip().splitlines()[0] if r.stderr.strip() else ""
            raise NnikError(f"host build of {prefix}.c failed: {first}")
        stdin = "\n".join(f"{a} {b}" for a, b in in_um.tolist()) + "\n"
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0")
        run = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, env=env)
    if run.returncode != 0:
        raise NnikError(f"host run of {prefix}.c failed: {run.stderr.strip()[:300]}")
    return run.stdout


def run_host_driver(c_dir: Path, prefix: str, in_um: np.ndarray, libs: tuple[str, ...] = (), cc: str = "gcc") -> dict:
    """Run PREFIX.c (any IK with the nnik API, e.g. a baseline) with the generic driver."""
    defines = [f"-DIK_FN={prefix}_ik", f'-DIK_HEADER="{prefix}.h"']
    out = build_and_run(c_dir, prefix, "ik_driver.c", defines, in_um, libs, cc)
    rows = np.array(out.split(), dtype=np.int64).reshape(-1, 3)
    return {"out": rows[:, :2], "flags": rows[:, 2]}
