"""What the report reads from MODEL_DIR: metrics.json (required), the model, the data, fixed_eval.npz."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nnik.errors import NnikError

METRICS_FILE = "metrics.json"
MODEL_FILE = "model.pt"
DATA_FILE = "data.npz"
FIXED_EVAL_FILE = "fixed_eval.npz"
FIXED_EVAL_ARRAYS = ("p_test", "q_true", "q_float", "q_fixed", "q_delivered")


@dataclass
class Inputs:
    model_dir: Path
    metrics: dict
    model: Any = None  # nnik.implementations.mlp.train.TrainedModel
    model_reason: str = ""
    scenario: Any = None  # nnik.machine.scenario.Scenario
    scenario_reason: str = ""
    data: Any = None  # nnik.machine.data.Dataset
    data_reason: str = ""
    fixed_eval: dict | None = None
    fixed_eval_reason: str = ""
    files: list[tuple[str, bool, str]] = field(default_factory=list)  # (file, present, note)


def load_metrics(model_dir: Path) -> dict:
    path = Path(model_dir) / METRICS_FILE
    if not path.is_file():
        raise NnikError("metrics.json not found (run `nnik run` or `nnik evaluate` first)", str(path))
    from nnik.files.metrics import read_metrics

    metrics = read_metrics(path)  # JSON, an object, and the shape of every key nnik reads back
    for k in ("name", "outputs", "unit"):
        if k not in metrics:
            raise NnikError(f"malformed metrics.json: missing {k!r}", str(path))
    return drop_stale(model_dir, metrics)


def short_exc(exc: BaseException) -> str:
    s = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {s[0]}" if s else type(exc).__name__


STALE = "the C in c/mlp/ changed since this was measured (run `nnik verify` again)"


def drop_stale(model_dir: Path, metrics: dict) -> dict:
    """Results of the MLP's C (host, avr, pic18) stay only while c/mlp/NAME.{c,h} hash as they
    did when the result was measured; others become {"not_run": STALE}."""
    from nnik.files.c_hash import dir_hash

    now = dir_hash(Path(model_dir) / "c" / "mlp", str(metrics.get("name", "")))
    if isinstance(metrics.get("host"), dict) and metrics["host"].get("c_hash") != now:
        metrics["host"] = {"not_run": STALE}
    for t, res in list((metrics.get("targets") or {}).items()):
        if isinstance(res, dict) and "not_run" not in res and res.get("c_hash") != now:
            metrics["targets"][t] = {"not_run": STALE}
    return mark_pick(model_dir, metrics)


def mark_pick(model_dir: Path, metrics: dict) -> dict:
    """The pick's row in the selection shows only figures measured on the bytes of c/NAME.c on
    disk (nnik.files.pick_state decides): a pick that is not the verified one, or not a finished one,
    keeps its name but says NOT verified, with both hashes and the command that mends it; a pick
    re-verified by `nnik verify` after a change shows the figures of its new bytes.
    metrics["pick_status"] holds the verdict."""
    from nnik.files.pick_state import CHECKS, status

    sel = metrics.get("selection")
    row = next((r for r in sel.get("implementations") or [] if isinstance(r, dict) and r.get("picked")), None) \
        if isinstance(sel, dict) else None
    if row is None:
        return metrics
    st = status(Path(model_dir), str(metrics.get("name", "")))
    metrics["pick_status"] = {"ok": st.ok, "state": st.state, "message": st.message, "file": st.file,
                              "disk_hash": st.disk_hash, "verified_hash": st.verified_hash}
    if st.ok:
        if row.get("c_hash") != st.disk_hash:  # re-verified bytes: their own figures
            row["host"] = st.check("host")
            row["targets"] = {k: st.check(k) or {"not_run": f"not run on these bytes ({st.disk_hash})"}
                              for k in CHECKS if k != "host"}
            row["cycles"] = {k: (st.check(k) or {}).get("cycles") for k in ("avr", "pic18")}
            row["flash_bytes"] = {k: (st.check(k) or {}).get("flash_bytes") for k in ("avr", "pic18")}
        return metrics
    why = {"not_run": f"NOT verified: {st.message}"}
    row["describe"] = f"{row.get('describe')} — NOT verified: {st.message}"
    row["host"] = dict(why)
    row["targets"] = {k: dict(why) for k in CHECKS if k != "host"}
    row["cycles"] = {"avr": None, "pic18": None}
    row["flash_bytes"] = {"avr": None, "pic18": None}
    row["pick_not_verified"] = st.message
    return metrics


def load_inputs(model_dir: Path) -> Inputs:
    model_dir = Path(model_dir)
    inp = Inputs(model_dir, load_metrics(model_dir))
    inp.files.append((METRICS_FILE, True, "required"))

    mp = model_dir / MODEL_FILE
    if mp.is_file():
        try:
            from nnik.implementations.mlp.train import TrainedModel

            inp.model = TrainedModel.load(mp)
            inp.scenario = inp.model.scenario
            inp.files.append((MODEL_FILE, True, "weights, scaling, scenario, training history"))
        except Exception as exc:  # noqa: BLE001 - a report must survive a bad model file
            inp.model_reason = f"{MODEL_FILE} could not be loaded ({short_exc(exc)})"
            inp.files.append((MODEL_FILE, False, inp.model_reason))
    else:
        inp.model_reason = f"{MODEL_FILE} not found in {model_dir}"
        inp.files.append((MODEL_FILE, False, "not found"))

    if inp.scenario is None:
        src = inp.metrics.get("scenario")
        if src and Path(src).is_file():
            try:
                from nnik.machine.scenario import load_scenario

                inp.scenario = load_scenario(src)
            except Exception as exc:  # noqa: BLE001
                inp.scenario_reason = f"scenario {src} could not be loaded ({short_exc(exc)})"
        else:
            inp.scenario_reason = f"{inp.model_reason or 'no model'}, and the scenario file {src!r} is not found"

    dp = model_dir / DATA_FILE
    if dp.is_file():
        try:
            from nnik.machine.data import Dataset

            inp.data = Dataset.load(dp)
            inp.files.append((DATA_FILE, True, "test split"))
        except Exception as exc:  # noqa: BLE001
            inp.data_reason = f"{DATA_FILE} could not be loaded ({short_exc(exc)})"
            inp.files.append((DATA_FILE, False, inp.data_reason))
    else:
        inp.data_reason = f"{DATA_FILE} not found in {model_dir}"
        inp.files.append((DATA_FILE, False, "not found"))

    fp = model_dir / FIXED_EVAL_FILE
    if fp.is_file():
        try:
            with np.load(fp) as z:
                missing = [a for a in FIXED_EVAL_ARRAYS if a not in z.files]
                if missing:
                    raise ValueError(f"missing arrays {', '.join(missing)}")
                fe = {a: np.asarray(z[a], dtype=np.float64) for a in FIXED_EVAL_ARRAYS}
            n = len(fe["p_test"])
            if any(a.ndim != 2 or len(a) != n for a in fe.values()) or n == 0:
                raise ValueError("arrays must be (N, 2) with the same N > 0")
            inp.fixed_eval = fe
            inp.files.append((FIXED_EVAL_FILE, True, f"{n} points of the fixed-point evaluation"))
        except Exception as exc:  # noqa: BLE001
            inp.fixed_eval_reason = f"{FIXED_EVAL_FILE} could not be read ({short_exc(exc)})"
            inp.files.append((FIXED_EVAL_FILE, False, inp.fixed_eval_reason))
    else:
        inp.fixed_eval_reason = f"{FIXED_EVAL_FILE} not found in {model_dir}"
        inp.files.append((FIXED_EVAL_FILE, False, "not found (fixed-point export not run)"))
    return inp
