"""The validation sweep: trained networks of the judged sizes, predicted vs measured on the
simulators (``python3 -m nnik.bench.mlp_cost sweep``; uses the pipeline to train them)."""

from __future__ import annotations

import datetime
import json
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from nnik.implementations.mlp.cost.kernels import kernel_key, model_kernel, write_c
from nnik.bench.mlp_cost.measure import run_profile
from nnik.implementations.mlp.cost.predict import estimate
from nnik.implementations.mlp.cost.calibrations import (BUILTIN_PROFILES, DEFAULT_KERNEL_KEY, REPO_ROOT, TARGETS,
                                                        cal_path, forget_loaded, profiles)
from nnik.implementations.mlp.cost.synthetic import DATASETS, in_domain_vectors

SWEEP_DIR = REPO_ROOT / "build" / "estimator_sweep"
SWEEP_ARCHS: tuple[tuple[int, ...], ...] = ((4,), (6,), (8,), (10,), (12,), (16,), (4, 4), (6, 6), (8, 8),
                                            (12, 8), (16, 16))
SWEEP_TANH = ("lerp_mr4", "minimax3_x11")


def _arch_label(hidden: Sequence[int], n_in: int = 2, n_out: int = 2) -> str:
    return "-".join(map(str, (n_in, *hidden, n_out)))


def sweep_model(hidden: tuple[int, ...], tanh: str | None, cache: Path = SWEEP_DIR,
                kernel: str | None = None):
    """A galvo_cba2012 network of the given hidden sizes, trained on a small iteration budget (cached), quantised."""
    from nnik.implementations.mlp import quantize as fx
    from nnik import pipeline
    from nnik.machine.data import Dataset
    from nnik.machine.scenario import load_scenario
    from nnik.implementations.mlp.train import TrainedModel

    out = Path(cache) / ("h" + "x".join(map(str, hidden)))
    if not (out / pipeline.MODEL_FILE).is_file():
        scn = load_scenario(DATASETS / "galvo_cba2012.toml")
        scn.network["hidden"] = tuple(hidden)
        scn.training.update(adam_steps=600, lbfgs_rounds=20, restarts=1)  # iterations: the same network anywhere
        scn.dataset.update(n_test=500)
        pipeline.generate(scn, out)
        pipeline.train(scn, out, progress=False)
    model = TrainedModel.load(out / pipeline.MODEL_FILE)
    ds = Dataset.load(out / pipeline.DATA_FILE)
    return fx.quantize(model, tanh_variant=tanh or None, calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]),
                       kernel=kernel)


def sweep(targets: Iterable[str] = TARGETS, archs: Sequence[tuple[int, ...]] = SWEEP_ARCHS,
          tanhs: Sequence[str] = SWEEP_TANH, profiles_: Sequence[str] | None = None, n_vec: int = 100,
          kernel: str | None = None, record: bool = False, verbose: bool = True) -> list[dict]:
    """Predicted vs measured cycles/flash/RAM of trained networks (galvo_cba2012 with the hidden
    sizes changed), on every profile of the targets. Rows: arch, tanh, target, profile,
    cycles_pred, cycles_meas, cycles_err_pct, flash_pred, flash_meas, flash_err_pct, ram_pred,
    ram_meas. record=True stores the summary in the calibration files."""
    from nnik.targets import available

    say = (lambda m: print(m, file=sys.stderr, flush=True)) if verbose else (lambda m: None)
    rows = []
    for target in targets:
        ok, why = available(target)
        if not ok:
            say(f"sweep: {target} skipped ({why})")
            continue
        profs = [p for p in (profiles_ or profiles(target)) if p in BUILTIN_PROFILES
                 and BUILTIN_PROFILES[p]["target"] == target]
        for hidden in archs:
            for tanh in tanhs:
                im = sweep_model(tuple(hidden), tanh, kernel=kernel)
                kern = model_kernel(im, kernel)
                tanh = im.tanh_variant
                d = SWEEP_DIR / ("h" + "x".join(map(str, hidden))) / f"{tanh}-{kernel_key(kern)}"
                csrc = write_c(im, d / "c", kernel=kern)
                vec = in_domain_vectors(im, n_vec, seed=4242)
                for prof in profs:
                    est = estimate(im, target, prof, kernel=kern)
                    r = run_profile(prof, csrc, im.name, vec, im.shape[-1], d / prof)
                    row = {"arch": _arch_label(hidden), "tanh": tanh, "target": target, "profile": prof,
                           "kernel": kern, "cycles_pred": round(est["cycles"], 1), "cycles_meas": float(r["cycles_mean"]),
                           "flash_pred": est["flash_bytes"], "flash_meas": int(r["model_flash_bytes"]),
                           "ram_pred": est["ram_bytes"], "ram_meas": int(r["model_ram_bytes"]),
                           "validated": est["validated"]}
                    row["cycles_err_pct"] = round((row["cycles_pred"] - row["cycles_meas"]) / row["cycles_meas"] * 100, 2)
                    row["flash_err_pct"] = round((row["flash_pred"] - row["flash_meas"]) / row["flash_meas"] * 100, 2)
                    rows.append(row)
                    say(f"{row['arch']:>9s} {tanh:13s} {prof:11s} cycles {row['cycles_pred']:8.0f} vs "
                        f"{row['cycles_meas']:8.0f} ({row['cycles_err_pct']:+.2f} %), flash {row['flash_pred']} vs "
                        f"{row['flash_meas']} ({row['flash_err_pct']:+.2f} %)")
    SWEEP_DIR.mkdir(parents=True, exist_ok=True)
    kkeys = sorted({kernel_key(r["kernel"]) for r in rows}) or [kernel_key(model_kernel(None, kernel))
                                                                 if kernel else DEFAULT_KERNEL_KEY]
    (SWEEP_DIR / f"sweep-{'+'.join(kkeys)}.json").write_text(
        json.dumps({"rows": rows, "summary": sweep_summary(rows)}, indent=1) + "\n")
    if record:
        _record_validation(rows)
    return rows


def _summ(rr: Sequence[dict]) -> dict:
    return {"networks": len(rr),
            "max_abs_cycles_err_pct": max(abs(r["cycles_err_pct"]) for r in rr),
            "mean_abs_cycles_err_pct": round(float(np.mean([abs(r["cycles_err_pct"]) for r in rr])), 2),
            "max_abs_flash_err_pct": max(abs(r["flash_err_pct"]) for r in rr),
            "max_abs_ram_err_bytes": max(abs(r["ram_pred"] - r["ram_meas"]) for r in rr)}


def sweep_summary(rows: Sequence[dict]) -> dict:
    """Per profile: the worst and mean errors, overall and per number of hidden layers."""
    out = {}
    for prof in sorted({r["profile"] for r in rows}):
        rr = [r for r in rows if r["profile"] == prof]
        out[prof] = _summ(rr)
        layers = sorted({r["arch"].count("-") - 1 for r in rr})
        out[prof]["by_layers"] = {str(n): _summ([r for r in rr if r["arch"].count("-") - 1 == n]) for n in layers}
    return out


def _record_validation(rows: Sequence[dict]) -> None:
    """Store the sweep summary per profile and kernel in the calibration files."""
    for kkey in sorted({kernel_key(r["kernel"]) for r in rows}):
        rk = [r for r in rows if kernel_key(r["kernel"]) == kkey]
        for prof, s in sweep_summary(rk).items():
            path = cal_path(prof)
            if not path.is_file():
                continue
            cal = json.loads(path.read_text())
            val = cal.get("validation") if isinstance(cal.get("validation"), dict) else {}
            val = {k: v for k, v in val.items() if isinstance(v, dict) and "networks" in v}  # per kernel
            val[kkey] = {**s, "archs": sorted({r["arch"] for r in rk if r["profile"] == prof}),
                         "tanh": sorted({r["tanh"] for r in rk if r["profile"] == prof}),
                         "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
                         "command": "python3 -m nnik.bench.mlp_cost sweep --record"
                                    + ("" if kkey in (DEFAULT_KERNEL_KEY, "portable") else f" --kernel {kkey}")}
            cal["validation"] = val
            path.write_text(json.dumps(cal, indent=1) + "\n")
    forget_loaded()


def format_sweep(rows: Sequence[dict]) -> str:
    hdr = (f"{'arch':>9s}  {'tanh':13s} {'profile':11s} {'cycles pred':>11s} {'measured':>9s} {'err %':>7s}  "
           f"{'flash pred':>10s} {'measured':>8s} {'err %':>6s}  {'RAM pred/meas':>13s}")
    lines = [hdr, "-" * len(hdr)]
    for r in rows:
        lines.append(f"{r['arch']:>9s}  {r['tanh']:13s} {r['profile']:11s} {r['cycles_pred']:11.0f} "
                     f"{r['cycles_meas']:9.0f} {r['cycles_err_pct']:+7.2f}  {r['flash_pred']:10d} {r['flash_meas']:8d} "
                     f"{r['flash_err_pct']:+6.2f}  {r['ram_pred']:>6d}/{r['ram_meas']:<6d}")
    for prof, s in sweep_summary(rows).items():
        lines.append(f"{prof}: {s['networks']} networks, max |cycles error| {s['max_abs_cycles_err_pct']:.2f} % "
                     f"(mean {s['mean_abs_cycles_err_pct']:.2f} %), max |flash error| {s['max_abs_flash_err_pct']:.2f} %, "
                     f"max |RAM error| {s['max_abs_ram_err_bytes']} B")
    return "\n".join(lines)
