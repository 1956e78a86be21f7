"""The G-code engine's C compiled for the host (gcc, UBSan + ASan) with a model's IK: a fast
check of nnik_gcode.c against the Python model without a simulator."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.firmware.arduino import ENGINE_C
from nnik.targets.toolchain import HARNESS_DIR
from nnik.targets.host import HOST_FLAGS

DRIVER = HARNESS_DIR / "arduino" / "nnik_gcode_host.c"


_BUILT: dict[str, Path] = {}


def build_engine_host(libdir: Path, name: str, cc: str = "gcc", defines: dict | None = None) -> Path:
    """The host engine for libdir's sources and defines, compiled once per process (cached by the
    sources' and flags' hash)."""
    import hashlib

    if shutil.which(cc) is None:
        raise NnikError(f"host C compiler {cc!r} not found")
    src = Path(libdir) / "src"
    files = [DRIVER, *(src / f for f in ENGINE_C), src / f"{name}.c"]
    flags = [*HOST_FLAGS, *(f"-D{k}={v}" for k, v in (defines or {}).items()), f"-I{src}"]
    h = hashlib.sha256(" ".join([cc, *flags]).encode())
    for f in [*files, *sorted(src.glob("*.h"))]:
        h.update(f.read_bytes())
    key = h.hexdigest()[:16]
    if key not in _BUILT or not _BUILT[key].is_file():
        exe = Path(tempfile.mkdtemp(prefix="nnik_engine_")) / "engine"
        r = subprocess.run([cc, *flags, *map(str, files), "-o", str(exe)], capture_output=True, text=True)
        if r.returncode != 0:
            raise NnikError(f"host build of the G-code engine failed: {r.stderr.strip()[:300]}")
        _BUILT[key] = exe
    return _BUILT[key]


def run_engine_host(libdir: Path, name: str, lines: list[str], cc: str = "gcc", defines: dict | None = None) -> dict:
    """{"start": steps (2,), "segments": (S, 6) d0 d1 ticks x y duty, "replies": [...],
    "overspeed": n} for the lines (the job's end flushes the planner); defines: the config's
    macros (MachineConfig.defines())."""
    exe = build_engine_host(libdir, name, cc, defines)
    data = b"".join((ln.encode("utf-8") if isinstance(ln, str) else ln) + b"\n" for ln in lines)
    run = subprocess.run([str(exe)], input=data, capture_output=True, env=dict(os.environ, ASAN_OPTIONS="detect_leaks=0"))
    if run.returncode != 0:
        raise NnikError(f"host run of the G-code engine failed: {run.stderr.decode(errors='replace')[:300]}")
    start, segs, replies, overspeed = None, [], [], -1
    for line in run.stdout.decode("latin-1").splitlines():
        tag, _, rest = line.partition(" ")
        if tag == "I":
            start = np.array(rest.split(), dtype=np.int64)
        elif tag == "S":
            segs.append([int(v) for v in rest.split()])
        elif tag == "R":
            replies.append(rest)
        elif tag == "O":
            overspeed = int(rest)
    return {"start": start, "segments": np.asarray(segs, dtype=np.int64).reshape(-1, 6), "replies": replies,
            "overspeed": overspeed}
