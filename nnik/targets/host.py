"""Host verification: compile the generated C with sanitizers and compare it with the integer model."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.emit.templating import CODEGEN
from nnik.implementations.mlp.fixedpoint import IntegerModel

HOST_FLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O1",
              "-fsanitize=undefined,address", "-fno-sanitize-recover=all"]


def verification_inputs(im: IntegerModel, p_test_mm: np.ndarray, n_random: int = 100_000, seed: int = 0) -> dict:
    """Named input sets in um: the test set, random in-domain points, corners/edges, out of domain."""
    lo, hi = im.inp.lo, im.inp.hi
    rng = np.random.default_rng(seed)
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]], dtype=np.int64)
    span = hi - lo
    outside = np.concatenate([
        corners + np.array([[-1, -1], [-1, 1], [1, -1], [1, 1]]),
        corners + np.array([[-1, -1], [-1, 1], [1, -1], [1, 1]]) * span,
        rng.integers(lo - span, hi + span + 1, (2000, 2)),
        np.array([[-(2**31), -(2**31)], [2**31 - 1, 2**31 - 1], [-(2**31), 2**31 - 1]], dtype=np.int64),
    ])
    outside = outside[np.any((outside < lo) | (outside > hi), axis=1)]
    return {
        "test": np.rint(p_test_mm * 1000).astype(np.int64),
        "random": rng.integers(lo, hi + 1, (n_random, 2)),
        "corners": corners,
        "outside": outside,
    }


def _build_and_run(c_dir: Path, prefix: str, driver: str, defines: list[str], in_um: np.ndarray,
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


def run_host(c_dir: Path, name: str, in_um: np.ndarray, cc: str = "gcc") -> dict:
    """Run NAME.c instrumented (-DNNIK_INSTRUMENT) with the MLP check driver: outputs, flags,
    pre-rounding totals and the overflow/saturation counters."""
    defines = ["-DNNIK_INSTRUMENT", f"-DNNIK_MODEL={name}", f'-DNNIK_MODEL_HEADER="{name}.h"']
    lines = _build_and_run(c_dir, name, "mlp_check.c", defines, in_um, cc=cc).strip().splitlines()
    tail = lines[-1].split()
    rows = np.array([ln.split() for ln in lines[:-1]], dtype=np.int64).reshape(-1, 5)
    return {"out": rows[:, 0:2], "flags": rows[:, 2], "total": rows[:, 3:5],
            "overflows": int(tail[1]), "saturations": int(tail[3])}


def verify_host(im: IntegerModel, c_dir: Path, inputs: dict) -> dict:
    """Compare C and the integer model on every input set; counts mismatches and instrumented events."""
    summary = {"points": 0, "mismatches": 0, "overflows": {}, "saturations": {}}
    for label, pts in inputs.items():
        c = run_host(c_dir, im.name, pts)
        total, out, flags = im.run(pts)
        bad = np.any(c["out"] != out, axis=1) | (c["flags"] != flags) | np.any(c["total"] != total, axis=1)
        summary["points"] += int(len(pts))
        summary["mismatches"] += int(bad.sum())
        summary["overflows"][label] = c["overflows"]
        summary["saturations"][label] = c["saturations"]
    summary["bit_exact"] = summary["mismatches"] == 0
    return summary


def run_host_driver(c_dir: Path, prefix: str, in_um: np.ndarray, libs: tuple[str, ...] = (), cc: str = "gcc") -> dict:
    """Run PREFIX.c (any IK with the nnik API, e.g. a baseline) with the generic driver."""
    defines = [f"-DIK_FN={prefix}_ik", f'-DIK_HEADER="{prefix}.h"']
    out = _build_and_run(c_dir, prefix, "ik_driver.c", defines, in_um, libs, cc)
    rows = np.array(out.split(), dtype=np.int64).reshape(-1, 3)
    return {"out": rows[:, :2], "flags": rows[:, 2]}
