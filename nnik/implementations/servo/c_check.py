"""Run a controller's C against its Python model: on the host (gcc with sanitizers, the driver
codegen/harness/host/ctl_driver.c) and on the ATmega328P under simavr (the IK harness times each
tick through codegen/harness/servo/nnik_ctl_wrap.c), from rows of (ref_x, ref_y, pos_x, pos_y)."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from nnik.emit.templating import CODEGEN
from nnik.errors import NnikError
from nnik.implementations.servo.emit_c import write_controller_c
from nnik.targets.host import HOST_FLAGS

AVR_MAX_TICKS = 900  # one simavr program holds every tick (16 bytes of flash each), so the state carries


def model_duties(controller, rows) -> np.ndarray:
    """The Python model's duty per row, from a reset."""
    controller.reset()
    return np.array([controller.tick((int(r[0]), int(r[1])), (int(r[2]), int(r[3]))) for r in rows], dtype=np.int64)


def host_duties(controller, rows, cc: str = "gcc", reset_before: tuple[int, ...] = ()) -> np.ndarray:
    """The controller's C compiled on the host: its duty per row, from a reset (and a reset before
    each row index in reset_before)."""
    return host_run(controller, rows, cc, reset_before)["duty"]


def model_sums(controller, rows) -> np.ndarray:
    """The Python model's weights' checksum after each row, from a reset (0 for a controller without)."""
    controller.reset()
    out = []
    for r in rows:
        controller.tick((int(r[0]), int(r[1])), (int(r[2]), int(r[3])))
        out.append(controller.checksum() if hasattr(controller, "checksum") else 0)
    return np.array(out, dtype=np.int64)


def host_run(controller, rows, cc: str = "gcc", reset_before: tuple[int, ...] = ()) -> dict:
    """As host_duties: {"duty": (N, 2), "sum": (N,) nnik_ctl_sum after each tick (0 without one)}."""
    if shutil.which(cc) is None:
        raise NnikError(f"host C compiler {cc!r} not found")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        srcs = write_controller_c(controller, d)
        exe = d / "drv"
        r = subprocess.run([cc, *HOST_FLAGS, "-I", str(d), str(CODEGEN / "harness" / "host" / "ctl_driver.c"),
                            *map(str, srcs), "-o", str(exe)], capture_output=True, text=True)
        if r.returncode != 0:
            raise NnikError(f"host build of the {controller.kind} controller failed: {r.stderr.strip()[:400]}")
        stdin = "".join(("r\n" if k in reset_before else "") + f"{a} {b} {c} {e}\n"
                        for k, (a, b, c, e) in enumerate(np.asarray(rows, dtype=np.int64).tolist()))
        run = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True,
                             env=dict(os.environ, ASAN_OPTIONS="detect_leaks=0"))
    if run.returncode != 0:
        raise NnikError(f"host run of the {controller.kind} controller failed: {run.stderr.strip()[:300]}")
    out = np.array(run.stdout.split(), dtype=np.int64).reshape(-1, 3)
    return {"duty": out[:, :2], "sum": out[:, 2]}


def avr_run(controller, rows, workdir: Path | None = None) -> dict:
    """The controller's C on the simulated ATmega328P (avr-gcc -Os, simavr): {"duty": (N, 2),
    "cycles": (N,) per tick, both axes, the wrapper's call included, "flash_bytes", "ram_bytes"}; a
    controller with a weights' checksum (c_arrays: the neural ones) also "sum": (N,) nnik_ctl_sum."""
    from nnik.targets.avr import run_avr

    rows = np.asarray(rows, dtype=np.int64)
    if not 1 <= len(rows) <= AVR_MAX_TICKS:
        raise NnikError(f"avr_run takes 1 .. {AVR_MAX_TICKS} ticks, not {len(rows)}")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(workdir or tmp)
        srcs = write_controller_c(controller, d / "src")
        summed = hasattr(controller, "c_arrays")
        wrap = CODEGEN / "harness" / "servo" / ("nnik_ctl_wrap_sum.c" if summed else "nnik_ctl_wrap.c")
        res = run_avr([wrap, *srcs], [d / "src"], "nnik_ctl", rows, workdir=d, n_out=3 if summed else 2,
                      batch_size=len(rows), progress=False)
    out = {"duty": res["outputs"][:, :2], "cycles": res["cycles"], "flash_bytes": res["model_flash_bytes"],
           "ram_bytes": res["model_ram_bytes"]}
    if summed:
        out["sum"] = res["outputs"][:, 2] & 0xFFFF
    return out
