"""The Uno's closed-loop library (issue 28 item 7, issue 29 item 8): an Arduino library with the servo
runtime (codegen/arduino/src/nnik_servo.c: encoder interrupts, PWM, the tick), the controller's C (a
neural one with its pretrained weights, copied from flash into its RAM weights on reset) and a
stored job (nnik.firmware.servo.job_pack), and the example sketch NAME_servo with a Makefile for
Debian's arduino-mk, as the open-loop export (nnik.firmware.arduino) writes its examples.

    export_servo_library(libdir, cfg, controller, ref_counts, start=(0, 0), name="xy_table")

The folder is written whole (nnik.files.replace_dir): an earlier export's folder is replaced, a
folder nnik did not write is refused.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from nnik.emit.c_text import c_comment_safe
from nnik.errors import NnikError
from nnik.firmware.arduino import _env, homepage
from nnik.firmware.servo.build import FLASH_BYTES, SRC, copy_runtime, tick_ocr1a
from nnik.firmware.servo.job_pack import data_header, pack
from nnik.implementations.servo.emit_c import write_controller_c

MARKER = ".nnik-servo-library"
VERSION = "0.1.0"
# the job's share of the flash: the sketch without it (core, Serial, runtime, controller) takes < 6 KiB
# with a fixed-gain controller, < 8.5 KiB with a learning one (its network, tanh and initial weights
# in flash and in RAM; measured 8.4 KiB for nn_axes;
# tests/firmware/servo/test_servo_export_nn.py builds ccc and both neural ones at their limit)
JOB_FLASH_BYTES = FLASH_BYTES - 6 * 1024
JOB_FLASH_BYTES_LEARNING = FLASH_BYTES - 17 * 512


def job_flash_bytes(controller) -> int:
    """The most flash a stored job may take beside this controller's sketch."""
    return JOB_FLASH_BYTES_LEARNING if hasattr(controller, "c_arrays") else JOB_FLASH_BYTES
REPORT_MS = 100


def write_library_files(d: Path, ctx: dict, properties_j2: str, ino_j2: str) -> None:
    """library.properties and the example ctx["example"] (its .ino and arduino-mk Makefile) in d."""
    env = _env()
    (d / "library.properties").write_text(env.get_template(properties_j2).render(**ctx))
    ex = d / "examples" / ctx["example"]
    ex.mkdir(parents=True)
    (ex / f"{ctx['example']}.ino").write_text(env.get_template(ino_j2).render(**ctx))
    (ex / "Makefile").write_text(env.get_template("Makefile.j2").render(**ctx))


def export_servo_library(libdir: Path, cfg, controller, ref_counts, start=(0, 0), name: str = "xy_table",
                         source: str = "nnik") -> dict:
    """Write the library; returns {"libname", "dir", "example", "job_bytes", "ticks"}. A job that
    is empty or does not fit the Uno's flash, or a tick Timer1 cannot make -> NnikError."""
    from nnik.files.replace_dir import check_replaceable, staged_folder

    ocr = tick_ocr1a(cfg.tick_s)
    import numpy as np

    ref = np.asarray(ref_counts, dtype=np.int64).reshape(-1, 2)
    if len(ref) == 0:
        raise NnikError("stored job: no ticks")
    data = pack(ref, start)
    room = job_flash_bytes(controller)
    if len(data) > room:
        raise NnikError(f"stored job: {len(data):,} bytes do not fit the Uno's flash ({room:,} B for the job beside "
                        f"the {controller.kind} controller; a shorter job, or the job split in parts)")
    libname = f"nnik_{name}_servo"
    final = Path(libdir)
    check_replaceable(final, MARKER, "Arduino servo library")
    example = f"{name}_servo"
    ctx = dict(name=name, libname=libname, version=VERSION, kind=controller.kind, tick_ms=f"{cfg.tick_s * 1e3:g}",
               homepage=homepage(), source=c_comment_safe(source), ticks=len(ref), job_bytes=len(data),
               x0=int(start[0]), y0=int(start[1]), report_ms=REPORT_MS, example=example,
               libdir_name=final.resolve().name)
    with staged_folder(final, MARKER, "Arduino servo library", f"{libname} {VERSION}: written by nnik\n") as d:
        src = d / "src"
        write_controller_c(controller, src, source)
        copy_runtime(src)
        for f in ("nnik_servo_job.c", "nnik_servo_job.h"):
            shutil.copy(SRC / f, src / f)
        (src / "nnik_servo_job_data.h").write_text(data_header(data, start, len(ref), source))
        # the tick's timer value, for the runtime (the sketch's build has no -D of nnik's)
        cfg_h = src / "nnik_servo_config.h"
        cfg_h.write_text(cfg_h.read_text().replace("#endif /* NNIK_SERVO_CONFIG_H */",
                                                   f"#ifndef NNIK_SERVO_OCR1A\n#define NNIK_SERVO_OCR1A {ocr}  /* the tick: "
                                                   f"{cfg.tick_s * 1e3:g} ms */\n#endif\n\n#endif /* NNIK_SERVO_CONFIG_H */"))
        write_library_files(d, ctx, "servo_library.properties.j2", "servo.ino.j2")
    return {"libname": libname, "dir": str(final), "example": example, "job_bytes": len(data), "ticks": len(ref)}
