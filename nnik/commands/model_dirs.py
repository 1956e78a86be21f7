"""The model directory (OUTDIR) the commands share: where a scenario's goes, and the checks a
command runs on one before it reads or writes anything."""

from __future__ import annotations

from pathlib import Path

from nnik import pipeline
from nnik.errors import NnikError
from nnik.files.outdir import check_model_dir, check_outdir
from nnik.report.console import console

OUTDIR_DEFAULT = "build/<name>/, <name> the scenario's"


def scenario_outdir(args, scn, create: bool = False) -> Path:
    """-o, or build/<name>/ (build/<name>-no-normalize/ with --no-normalize), checked."""
    normalize = not getattr(args, "no_normalize", False)
    out = Path(args.outdir) if args.outdir else pipeline.default_outdir(scn, normalize)
    return check_outdir(out, create=create)


def warn_training(model) -> None:
    """The user's wall-clock cap cut training short: the model depends on this machine's load."""
    stop = getattr(model, "stopped_by", "budget")
    if stop != "budget":
        console.print(f"[bold yellow]warning:[/bold yellow] training stopped by the {stop.replace('_', '-')} cap "
                      f"(\\[training] max_seconds) before its iteration budget; the result depends on machine load and is not reproducible "
                      f"(recorded as training.stopped_by in metrics.json)")


def trained_for(scn, out: Path) -> bool:
    """OUTDIR holds data.npz and model.pt of this very scenario (a rerun resumes, no retraining)."""
    if not ((out / pipeline.DATA_FILE).is_file() and (out / pipeline.MODEL_FILE).is_file()
            and (out / pipeline.METRICS_FILE).is_file()):
        return False
    try:
        model, _ = pipeline.load_pair(out)
    except NnikError:
        return False
    return model.scenario.fingerprint == scn.fingerprint


EVALUATED_KEYS = ("name", "unit", "outputs", "network", "dataset", "float", "affine_only", "onnx")


def evaluated_dir(model_dir) -> Path:
    """A model directory whose metrics.json `nnik evaluate` wrote (checked before anything runs)."""
    out = check_model_dir(model_dir, pipeline.C_DIR)
    missing = [k for k in EVALUATED_KEYS if k not in pipeline.load_metrics(out)]
    if missing:
        raise NnikError(f"metrics.json lacks {', '.join(missing)} (run `nnik evaluate` again)", str(out))
    return out


def add_model_dir(p) -> None:
    p.add_argument("model_dir", metavar="MODEL_DIR", help="a model directory `nnik run` wrote (build/<name>/)")
