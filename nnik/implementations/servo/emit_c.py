"""The controller's C: the generated nnik_servo_config.h (codegen/arduino/templates/
servo_config.h.j2, the kind's macro and its gains from the controller's c_defines()) and the
controller sources from codegen/arduino/src/ (all of them: each compiles to nothing unless its
kind's macro is defined, so a build may compile the whole folder)."""

from __future__ import annotations

import shutil
from pathlib import Path

import jinja2

from nnik.emit.templating import CODEGEN

SRC = CODEGEN / "arduino" / "src"
TEMPLATES = CODEGEN / "arduino" / "templates"
SOURCES = ("nnik_ctl_pid.c", "nnik_ctl_pdff.c", "nnik_ctl_ccc.c", "nnik_imath.c")
HEADERS = ("nnik_ctl.h", "nnik_ctl_fix.h", "nnik_ctl_pid_axis.h", "nnik_imath.h")
FORMATS = {"KP": "Q8.8 duty per count", "KI": "Q0.16 duty per count per tick", "KD": "Q8.8 duty per count per tick",
           "KV": "Q8.8 duty per count per tick (over the window)", "KA": "Q8.8 duty per count per tick^2 (window)",
           "KCP": "contour P, Q8.8 duty per count", "KCD": "contour D, Q8.8 duty per count per tick"}


def servo_config_h(controller, source: str = "nnik") -> str:
    """The text of nnik_servo_config.h for this controller."""
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)), undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True)
    defines = controller.c_defines()
    formats = {k: FORMATS.get(k.split("_")[1], "") + f" ({k[-1]})" for k in defines if k.count("_") == 2}
    return env.get_template("servo_config.h.j2").render(defines=defines, formats=formats,
                                                         source=source.replace("*/", "* /"))


def write_controller_c(controller, outdir: Path, source: str = "nnik") -> list[Path]:
    """nnik_servo_config.h and the controller sources and headers in outdir; returns the .c paths."""
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "nnik_servo_config.h").write_text(servo_config_h(controller, source))
    for f in SOURCES + HEADERS:
        shutil.copy(SRC / f, outdir / f)
    return [outdir / f for f in SOURCES]
