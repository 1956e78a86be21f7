"""The controller's C: the generated nnik_servo_config.h (codegen/arduino/templates/
servo_config.h.j2, the kind's macro and its gains from the controller's c_defines()) and the
controller sources from codegen/arduino/src/ (all of them: each compiles to nothing unless its
kind's macro is defined, so a build may compile the whole folder); for a neural controller also its
initial weights (c_arrays(), as brace-list macros) and its generated tanh (nnik_nn_tanh.h)."""

from __future__ import annotations

import shutil
from pathlib import Path

import jinja2

from nnik.emit.templating import CODEGEN

SRC = CODEGEN / "arduino" / "src"
TEMPLATES = CODEGEN / "arduino" / "templates"
SOURCES = ("nnik_ctl_pid.c", "nnik_ctl_pdff.c", "nnik_ctl_ccc.c", "nnik_ctl_nn_axes.c", "nnik_ctl_nn_vector.c",
           "nnik_imath.c")
HEADERS = ("nnik_ctl.h", "nnik_ctl_fix.h", "nnik_ctl_pid_axis.h", "nnik_ctl_nn.h", "nnik_imath.h")
# the neural controllers' activation, generated (nnik.implementations.mlp.tanh.render_tanh_c), and
# the flash-table header it includes (codegen/runtime)
NN_GENERATED = ("nnik_nn_tanh.h", "nnik_flash.h")
FORMATS = {"KP": "Q8.8 duty per count", "KI": "Q0.16 duty per count per tick", "KD": "Q8.8 duty per count per tick",
           "KV": "Q8.8 duty per count per tick (over the window)", "KA": "Q8.8 duty per count per tick^2 (window)",
           "KCP": "contour P, Q8.8 duty per count", "KCD": "contour D, Q8.8 duty per count per tick"}


def servo_config_h(controller, source: str = "nnik") -> str:
    """The text of nnik_servo_config.h for this controller."""
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)), undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True)
    defines = controller.c_defines()
    formats = {k: FORMATS.get(k.split("_")[1], "") + f" ({k[-1]})" for k in defines if k.count("_") == 2}
    arrays = {k: [", ".join(f"{v}L" for v in vals[i:i + 6]) for i in range(0, len(vals), 6)]
              for k, vals in (controller.c_arrays() if hasattr(controller, "c_arrays") else {}).items()}
    return env.get_template("servo_config.h.j2").render(defines=defines, formats=formats, arrays=arrays,
                                                         source=source.replace("*/", "* /"))


def write_controller_c(controller, outdir: Path, source: str = "nnik") -> list[Path]:
    """nnik_servo_config.h and the controller sources and headers in outdir; returns the .c paths."""
    outdir.mkdir(parents=True, exist_ok=True)
    (outdir / "nnik_servo_config.h").write_text(servo_config_h(controller, source))
    for f in SOURCES + HEADERS:
        shutil.copy(SRC / f, outdir / f)
    if hasattr(controller, "c_arrays"):  # a neural controller: its tanh
        from nnik.implementations.servo.nn.formats import tanh_c

        (outdir / NN_GENERATED[0]).write_text(tanh_c())
        shutil.copy(CODEGEN / "runtime" / NN_GENERATED[1], outdir / NN_GENERATED[1])
    return [outdir / f for f in SOURCES]
