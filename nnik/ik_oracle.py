"""The bit-exact Python twin of whatever IK sits in OUTDIR/c/NAME.c (one place to swap it)."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

IkFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def ik_oracle(outdir: Path) -> IkFn:
    """in_um (N, 2) int64 -> (out (N, 2) int64 actuator units, flags (N,) int64: 1 if clamped).

    Today c/NAME.c is the MLP of the scenario's kernel, so its integer model answers."""
    from nnik import pipeline

    model = pipeline.TrainedModel.load(Path(outdir) / pipeline.MODEL_FILE)
    ds = pipeline.Dataset.load(Path(outdir) / pipeline.DATA_FILE)
    im = pipeline.quantize_kernel(model, ds, model.scenario.export["kernel"])

    def ik(in_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        _, out, flags = im.run(np.asarray(in_um, dtype=np.int64).reshape(-1, 2))
        return out, flags

    return ik


def ik_sources(outdir: Path, name: str) -> Path:
    """The directory whose NAME.c/NAME.h ik_oracle() answers for: the MLP pipeline's C
    (OUTDIR/c/mlp/) where it exists, else OUTDIR/c/."""
    from nnik import pipeline
    from nnik.errors import NnikError

    for d in (Path(outdir) / getattr(pipeline, "MLP_DIR", pipeline.C_DIR), Path(outdir) / pipeline.C_DIR):
        if (d / f"{name}.c").is_file() and (d / f"{name}.h").is_file():
            return d
    raise NnikError(f"no generated C {name}.c (run `nnik export {outdir}` first)", str(outdir))


def load_scenario_of(outdir: Path):
    """The scenario a model directory was trained for."""
    from nnik import pipeline

    return pipeline.TrainedModel.load(Path(outdir) / pipeline.MODEL_FILE).scenario
