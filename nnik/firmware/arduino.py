"""`nnik export OUTDIR --arduino DIR`: an Arduino / PlatformIO library around OUTDIR/c/NAME.c.

DIR/library.properties, DIR/library.json, DIR/src/ (NAME.c/.h, the runtime headers, the G-code
engine and its configuration), DIR/examples/NAME_selftest/ (golden vectors from the integer
model, PASS/FAIL and cycles per call) and DIR/examples/NAME_gcode/ (G-code over Serial to two
stepper drivers); each example has a Makefile for Debian's arduino-mk.
"""

from __future__ import annotations

import shutil
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import jinja2
import numpy as np

from nnik.errors import NnikError
from nnik.machine.domain import domain_um
from nnik.emit.templating import CODEGEN, RUNTIME, environment
from nnik.firmware.config import FEATURES, MachineConfig, default_machine
from nnik.firmware.grbl_settings import grbl_settings, settings_c_string
from nnik.emit.c_text import c_comment_safe

ARDUINO = CODEGEN / "arduino"
ENGINE_C = ("nnik_gc_init.c", "nnik_gc_read.c", "nnik_gcode.c", "nnik_gc_segments.c", "nnik_gc_parse.c", "nnik_gc_tool.c",
            "nnik_gc_geom.c", "nnik_imath.c", "nnik_plan.c", "nnik_plan_sample.c", "nnik_shaper.c")
ENGINE_FILES = (*ENGINE_C, "nnik_gcode.h", "nnik_gc_block.h", "nnik_gc_tool.h", "nnik_gc_geom.h", "nnik_imath.h",
                "nnik_plan.h", "nnik_shaper.h", "nnik_grbl.h", "nnik_grbl.c")
VERSION = "0.1.0"
N_GOLDEN = 64


@lru_cache(maxsize=1)
def _env() -> jinja2.Environment:
    return environment().overlay(loader=jinja2.FileSystemLoader(str(ARDUINO / "templates")))


def golden_vectors(scn, n: int = N_GOLDEN, seed: int = 0) -> np.ndarray:
    """Corners, centre, edge midpoints, random points of the domain and a few outside it (um)."""
    lo, hi = domain_um(scn.workspace)
    mid = (lo + hi) // 2
    span = hi - lo
    fixed = [[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]], mid,
             [mid[0], lo[1]], [mid[0], hi[1]], [lo[0], mid[1]], [hi[0], mid[1]],
             [lo[0] - 1, mid[1]], [hi[0] + span[0], hi[1] + span[1]], [lo[0] - span[0], lo[1] - span[1]]]
    rng = np.random.default_rng(seed)
    rand = rng.integers(lo, hi + 1, (max(0, n - len(fixed)), 2))
    return np.concatenate([np.asarray(fixed, dtype=np.int64), rand])


MARKER = ".nnik-arduino-library"  # in every folder this export wrote: the folder it may replace


def check_libdir(libdir: Path, outdir: Path) -> Path:
    """DIR of --arduino, checked before anything is written: new, empty or an earlier export's
    folder (its marker), and never the model directory or a folder holding it."""
    from nnik.files.replace_dir import check_replaceable

    final, model = Path(libdir).resolve(), Path(outdir).resolve()
    if final == model or final in model.parents:
        raise NnikError("the Arduino library would replace the model directory that it is exported from; give a new folder",
                        str(libdir), "--arduino")
    check_replaceable(Path(libdir), MARKER, "Arduino library")
    return Path(libdir)


def export_arduino(outdir: Path, libdir: Path, machine: MachineConfig | None = None, model=None) -> dict:
    """Write the library as a whole (nnik.files.replace_dir: an earlier export's folder is replaced
    with nothing of it left, a folder nnik did not write is refused); returns {"libname", "dir",
    "name", "machine", "golden"}. model: OUTDIR as a job has read it (nnik.firmware.model_dir),
    else it is read here."""
    from nnik.files.replace_dir import staged_folder
    from nnik.firmware.model_dir import ModelDir

    outdir, final = Path(outdir), check_libdir(libdir, outdir)
    model = model if model is not None else ModelDir.load(outdir)
    scn = model.scenario
    name = scn.name
    c_dir = model.c_sources()
    if machine is None:
        _default(scn)  # refused before anything is written
    ik = model.ik
    vec = golden_vectors(scn)
    out, flags = ik(vec)
    rows = [[int(a), int(b), int(c), int(d), int(f)] for (a, b), (c, d), f in zip(vec.tolist(), out.tolist(), flags.tolist())]
    what, hash_ = model.label()
    libname = f"nnik_{name}"
    sender, left_out, uno_flash = machine is None, (), 0
    machine = machine or _default(scn)
    with staged_folder(final, MARKER, "Arduino library", f"{libname} {VERSION}: written by nnik export --arduino\n") \
            as libdir:
        _write_library(libdir, final, scn, c_dir, machine, ik, rows, what, hash_, libname)
        if sender:  # the Uno's build carries the options that fit its flash (nnik.firmware.uno_fit)
            from nnik.firmware.uno_fit import uno_features

            features, left_out, uno_flash = uno_features(libdir, name, machine)
            if left_out:
                machine = replace(machine, features=features)
                _write_library(libdir, final, scn, c_dir, machine, ik, rows, what, hash_, libname)
    return {"libname": libname, "dir": str(final), "name": name, "machine": machine, "golden": len(rows),
            "uno_left_out": list(left_out), "uno_fits": uno_flash != -1}


def _default(scn) -> MachineConfig:
    try:
        return default_machine(scn)
    except ValueError as exc:  # [motion] shaper "auto" picks per job: a library needs a fixed one
        raise NnikError(f"{exc}; the library needs a fixed shaper", scn.source, "[motion] shaper") from None


def _write_library(libdir: Path, final: Path, scn, c_dir: Path, machine: MachineConfig, ik, rows, what: str,
                   hash_: str, libname: str) -> None:
    name = scn.name
    src = libdir / "src"
    src.mkdir(parents=True, exist_ok=True)
    for f in [c_dir / f"{name}.c", c_dir / f"{name}.h", *sorted(RUNTIME.glob("*.h"))]:
        shutil.copy(f, src / f.name)
    for f in ENGINE_FILES:
        shutil.copy(ARDUINO / "src" / f, src / f)
    ctx = dict(name=name, scenario=c_comment_safe(scn.source), libname=libname, version=VERSION,
               shape=c_comment_safe(what).replace('"', "'"),
               description=c_comment_safe(scn.raw.get("description") or name), unit=scn.unit, outputs=scn.outputs, model_hash=hash_,
               origin=list(machine.origin_um), seg_um=machine.seg_um, tick_hz=machine.tick_hz, homepage=homepage(),
               rapid_um_min=machine.rapid_um_min, feed_um_min=machine.feed_um_min, rows=rows, n=len(rows),
               tool=machine.tool, tool_defines=machine.defines(), sample_hz=machine.sample_hz,
               build_options=[f"NNIK_GC_{f.upper()}" for f in sorted(FEATURES)],
               shaper=machine.shaper,
               grbl_settings=settings_c_string(grbl_settings(machine, scn.workspace, ik, machine.bounds_um is not None)))
    env = _env()
    files = {
        libdir / "library.properties": "library.properties.j2",
        libdir / "library.json": "library.json.j2",
        src / "nnik_gcode_config.h": "gcode_config.h.j2",
        src / "nnik_grbl_config.h": "grbl_config.h.j2",
        libdir / "examples" / f"{name}_selftest" / f"{name}_selftest.ino": "selftest.ino.j2",
        libdir / "examples" / f"{name}_gcode" / f"{name}_gcode.ino": "gcode.ino.j2",
    }
    for example in (f"{name}_selftest", f"{name}_gcode"):
        files[libdir / "examples" / example / "Makefile"] = "Makefile.j2"
    for path, tmpl in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(env.get_template(tmpl).render(**ctx, example=path.parent.name, libdir_name=final.resolve().name))


def homepage() -> str:
    """The project's homepage, from one place: pyproject.toml's [project.urls] Homepage (the
    source checkout's file, else the installed package's metadata). Empty when none is set, as
    now: nnik publishes none, and the README says how to fill the library's url= field."""
    import tomllib
    from importlib import metadata

    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    if pyproject.is_file():
        urls = tomllib.loads(pyproject.read_text()).get("project", {}).get("urls", {})
        return str(urls.get("Homepage", ""))
    try:
        entries = metadata.metadata("nnik").get_all("Project-URL") or []
    except metadata.PackageNotFoundError:
        return ""
    return next((u.strip() for label, _, u in (e.partition(",") for e in entries) if label.strip() == "Homepage"), "")
