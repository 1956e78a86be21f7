"""The bit-exact Python twin of whatever IK sits in OUTDIR/c/NAME.c (one place to swap it)."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

IkFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def picked_implementation(outdir: Path, st=None):
    """The implementation nnik run picked (refitted), when OUTDIR holds a finished pick whose
    c/NAME.c is the C that was verified (:mod:`nnik.files.pick_state`, else the one-line NnikError it
    gives); None when there is no finished pick or the pick takes inputs in a unit other than 1 um.
    Commands that deliver firmware call ``pick_state.require_deliverable`` first, so for them the
    None cases never get here; the fallback to the MLP below serves the library's own tests.
    st: the directory's pick_state.status when the caller has read it already."""
    from nnik.files import pick_state
    from nnik.firmware.pick_verify import pick_implementation

    st = st or pick_state.status(Path(outdir))
    if st.state == "none" or (st.marker or {}).get("input_unit_um", 1.0) != 1.0:
        return None
    return pick_implementation(Path(outdir), st)


def ik_oracle(outdir: Path) -> IkFn:
    """in_um (N, 2) int64 -> (out (N, 2) int64 actuator units, flags (N,) int64: 1 if clamped).

    The pick's integer model when nnik run picked one (c/NAME.c), else the MLP of the scenario's
    kernel (c/mlp/NAME.c)."""
    return ik_of(outdir, picked_implementation(outdir))


def ik_of(outdir: Path, impl) -> IkFn:
    """ik_oracle's function for the pick impl (picked_implementation's answer; None: the MLP)."""
    from nnik import pipeline

    if impl is not None:
        def ik(in_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            r = impl.run(np.asarray(in_um, dtype=np.int64).reshape(-1, 2))
            return r.out, r.flags

        return ik
    model, ds = pipeline.load_pair(Path(outdir))
    im = pipeline.quantize_kernel(model, ds, model.scenario.export["kernel"])

    def ik(in_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        _, out, flags = im.run(np.asarray(in_um, dtype=np.int64).reshape(-1, 2))
        return out, flags

    return ik


def ik_sources(outdir: Path, name: str, picked: bool | None = None) -> Path:
    """The directory whose NAME.c/NAME.h ik_oracle() answers for: OUTDIR/c/ when it holds the
    pick, else the MLP pipeline's C (OUTDIR/c/mlp/). picked: whether it holds one, when known."""
    from nnik import pipeline
    from nnik.errors import NnikError

    if picked is None:
        picked = picked_implementation(outdir) is not None
    dirs = [Path(outdir) / pipeline.C_DIR] if picked else []
    dirs.append(Path(outdir) / pipeline.MLP_DIR)
    for d in dirs:
        if (d / f"{name}.c").is_file() and (d / f"{name}.h").is_file():
            return d
    raise NnikError(f"no generated C {name}.c (run `nnik export {outdir}` first)", str(outdir))


def load_scenario_of(outdir: Path):
    """The scenario a model directory was trained for."""
    from nnik import pipeline

    return pipeline.TrainedModel.load(Path(outdir) / pipeline.MODEL_FILE).scenario
