"""The MLP family's own files, beyond the C of its best in c/alt/mlp/ that every family has:
the trained network (model.pt, model.onnx), its float and fixed-point accuracy in metrics.json,
c/mlp/ with both kernels and the float IK (the speed reference), and their verification on the
host and the simulated chips (metrics "host" and "targets"; the report's MLP rows).

The network itself is trained once, by the family's fit (:mod:`nnik.implementations.mlp.family`)
inside the pipeline's ladder; :func:`keep` writes it here. ``nnik train`` (:func:`train`) trains
it on its own, for the MLP's experiments.
"""

from __future__ import annotations

import math

from pathlib import Path

import numpy as np
from sklearn.linear_model import LinearRegression

from nnik.errors import NnikError
from nnik.files import pick_state
from nnik.files.c_hash import dir_hash
from nnik.files.metrics import (C_DIR, DATA_FILE, FIXED_EVAL_FILE, METRICS_FILE, MLP_DIR, MODEL_FILE, ONNX_FILE,
                                load_metrics, write_metrics)
from nnik.implementations.mlp.evaluate import error_stats, position_error_um, relative_pct
from nnik.implementations.mlp.onnx_export import ONNX_TOLERANCE, check_onnx, export_onnx
from nnik.implementations.mlp.train import MAX_FIT_ROWS, TrainedModel, train_model
from nnik.machine.data import Dataset
from nnik.machine.scenario import Scenario


def check_data_matches(scn: Scenario, ds: Dataset, outdir: Path, what: str = "the scenario") -> None:
    """data.npz must come from this very scenario (name and fingerprint)."""
    got = ds.meta.get("scenario_hash")
    if got != scn.fingerprint:
        was = ds.meta.get("scenario", "?")
        raise NnikError(f"data.npz was generated from {'scenario ' + repr(was) if was != scn.name else 'another version of it'}"
                        f", not from {what} {scn.name!r} ({scn.source}); run `nnik generate` (or `nnik run`) again",
                        str(outdir / DATA_FILE))


def load_pair(outdir: Path) -> tuple[TrainedModel, Dataset]:
    """model.pt and data.npz of OUTDIR, checked to belong to the same scenario."""
    model = TrainedModel.load(outdir / MODEL_FILE)
    ds = Dataset.load(outdir / DATA_FILE)
    check_data_matches(model.scenario, ds, outdir, "the model's scenario")
    return model, ds


def train(scn: Scenario, outdir: Path, normalize: bool | None = None, progress: bool = True) -> TrainedModel:
    ds = Dataset.load(outdir / DATA_FILE)
    check_data_matches(scn, ds, outdir)
    pick_state.invalidate(outdir)
    model = train_model(scn, ds, normalize=normalize, progress=progress)
    model.save(outdir / MODEL_FILE)
    export_onnx(model, outdir / ONNX_FILE)
    return model


def affine_baseline(ds: Dataset) -> np.ndarray:
    """The skeptic's first baseline: a least-squares affine map fitted on the training set."""
    lr = LinearRegression().fit(ds.p["train"], ds.q["train"])
    return lr.predict(ds.p["test"])


def evaluate(outdir: Path) -> dict:
    model, ds = load_pair(outdir)
    scn = model.scenario
    p, q = ds.p["test"], ds.q["test"]
    pred = model.predict(p)
    onnx_diff = check_onnx(model, outdir / ONNX_FILE, p)
    if not onnx_diff <= ONNX_TOLERANCE:
        raise NnikError(f"ONNX model differs from torch by {onnx_diff:.3g} (> {ONNX_TOLERANCE:g})", str(outdir / ONNX_FILE))
    shape = list(model.net.shape)
    inputs = pick_state.inputs_hash(outdir)
    # the same model.pt and data.npz as the metrics on disk describe: the accuracy is measured
    # again and every later section (the selection, the pick) stays; else they go with the old model
    same = _evaluated_inputs(outdir) == inputs
    if not same:
        pick_state.invalidate(outdir)
    seconds = model.train_seconds if math.isfinite(model.train_seconds) else None  # its time file may be gone
    metrics = {
        "evaluated_inputs": inputs,
        "name": scn.name,
        "scenario": scn.source,
        "mechanism": scn.mechanism.describe(),
        "actuator": scn.actuator.describe(),
        "outputs": scn.outputs,
        "unit": scn.unit,
        "network": {
            "shape": shape,
            "mode": scn.network["mode"],
            "normalize": model.normalize,
            "parameters": int(sum(a * b + b for a, b in zip(shape[:-1], shape[1:]))),
        },
        "dataset": {**{f"n_{s}": int(len(ds.p[s])) for s in ds.p}, "truth": ds.meta["truth"]},
        "float": {**error_stats(pred, q), "rel_pct": relative_pct(pred, q)},
        "affine_only": error_stats(affine_baseline(ds), q),
        "onnx": {"max_abs_diff": onnx_diff, "tolerance": ONNX_TOLERANCE, "ok": True},
        "train_seconds": seconds,
        "training": {"stopped_by": model.stopped_by, "seconds": seconds,
                     "max_seconds": scn.training["max_seconds"],
                     "restarts_run": len({h["restart"] for h in model.history}),
                     "lbfgs_rounds_run": sum(h["phase"] == "lbfgs" for h in model.history),
                     "rows_fitted": min(int(len(ds.p["train"])), MAX_FIT_ROWS)},
    }
    pos = position_error_um(scn, pred, p)
    if pos is not None:
        metrics["float"]["position_um"] = pos
    write_metrics(outdir, metrics, merge=same)
    return metrics


def _evaluated_inputs(outdir: Path) -> dict | None:
    """The hashes of model.pt and data.npz that metrics.json on disk was made from (None if unknown)."""
    from nnik.files.metrics import read_metrics

    path = outdir / METRICS_FILE
    try:
        old = read_metrics(path) if path.is_file() else {}
    except NnikError:
        return None
    sel = old.get("selection")
    return old.get("evaluated_inputs") or (sel.get("inputs") if isinstance(sel, dict) else None)



def keep(problem, outdir: Path) -> TrainedModel:
    """Write the network the family's fit trained for the scenario's own configuration (model.pt,
    model.onnx) and its accuracy (metrics.json, rewritten: no pick until the pipeline picks again)."""
    from nnik.implementations.mlp.family import trained

    model = trained(problem)
    if model is None:
        raise NnikError("the mlp family's fit did not train the scenario's network", str(outdir))
    check_data_matches(problem.scn, problem.dataset, outdir)
    pick_state.invalidate(outdir)
    model.save(outdir / MODEL_FILE)
    export_onnx(model, outdir / ONNX_FILE)
    evaluate(outdir)
    return model


# ---- fixed point: quantise, generate C, verify on the host -----------------------------------
def _truth_for_um(scn, in_um: np.ndarray, fallback_q: np.ndarray) -> np.ndarray:
    """The exact IK at the integer-um inputs the C sees (analytic), or the held-out rows."""
    from nnik.machine.data import exact_targets

    return exact_targets(scn, in_um / 1000.0) if scn.mechanism.analytic else fallback_q


def quantize_kernel(model: TrainedModel, ds: Dataset, kernel: str):
    """The scenario's integer model for one kernel ("fast" or "portable")."""
    from nnik.implementations.mlp import quantize as fx

    scn = model.scenario
    tanh = None if scn.export["tanh"] == "default" else scn.export["tanh"]
    return fx.quantize(model, tanh_variant=tanh, weight_bits=scn.export["weight_bits"],
                       calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]), kernel=kernel)


def other_kernel(kernel: str) -> str:
    return "portable" if kernel == "fast" else "fast"


def export(outdir: Path):
    """Quantise model.pt, write OUTDIR/c/mlp/NAME.{h,c} (the scenario's kernel) and, for
    comparison, OUTDIR/c/mlp/<other kernel>/NAME.{h,c}, and the float IK (the speed reference) in OUTDIR/c/;
    returns both integer models (scenario's kernel first). Nothing is written unless every
    file was generated and the range analysis held (see nnik.files.atomic_write)."""
    from nnik.implementations.mlp import quantize as fx
    from nnik.files.atomic_write import Staged, replacing
    from nnik.implementations.mlp.export import render_model_c

    model, ds = load_pair(outdir)
    scn = model.scenario
    staged = Staged(outdir)
    im = quantize_kernel(model, ds, scn.export["kernel"])
    staged.add(render_model_c(im, scn.source), MLP_DIR)
    alt_im = quantize_kernel(model, ds, other_kernel(im.kernel))
    staged.add(render_model_c(alt_im, scn.source), Path(MLP_DIR) / alt_im.kernel)
    in_um = np.rint(ds.p["test"] * 1000).astype(np.int64)
    truth = _truth_for_um(scn, in_um, ds.q["test"])
    baselines = _export_baselines(scn, staged)
    total, delivered, _ = im.run(in_um)
    pre = total / float(2**im.out.F)
    stats = error_stats(pre, truth)
    ranges = fx.range_report(im, np.concatenate([fx.dense_inputs_um(im), in_um]))
    if not all(r["within_bound"] for r in ranges):
        raise NnikError("range analysis failed: a tensor exceeded its proven bound", str(outdir))
    tanh_stats = im.tanh_summary()
    staged.commit()
    write_metrics(outdir, {
        "fixed": {**stats, "delivered_max_abs": np.abs(delivered - truth).max(0).tolist(),
                  "delivered_rms": np.sqrt(((delivered - truth) ** 2).mean(0)).tolist(),
                  "tanh_variant": im.tanh_variant, "weight_bits": im.weight_bits, "kernel": im.kernel,
                  "weights_bytes": im.weights_bytes(), "model_hash": im.model_hash(),
                  "q_formats": im.formats(), "ranges": ranges},
        "tanh": {"variant": im.tanh_variant, **{k: tanh_stats[k] for k in ("max_lsb", "rms_lsb") if k in tanh_stats}},
        "baselines": baselines,
    })
    with replacing(outdir / FIXED_EVAL_FILE) as tmp:
        np.savez_compressed(tmp, p_test=ds.p["test"], q_true=truth, q_float=model.predict(ds.p["test"]),
                            q_fixed=pre, q_delivered=delivered)
    return im, alt_im


def mlp_flash_bytes(im) -> int:
    """Bytes of constant tables the MLP needs: weights, biases and the tanh table."""
    return im.weights_bytes() + im.tanh_bytes()


def _export_baselines(scn, staged) -> dict:
    """Stage c/NAME_float.{h,c}, the float math.h IK, where a closed form exists. (What a firmware
    engineer would write as a table is a point of the lut family: its best is in the selection.)"""
    from nnik.targets import float_ik

    out: dict = {}
    reason = float_ik.float_unavailable_reason(scn)
    if reason is None:
        staged.add(float_ik.render_float_c(scn), C_DIR)
        out["float"] = {"available": True, "file": f"{scn.name}_float.c"}
    else:
        out["float"] = {"available": False, "reason": reason}
    return out


def _verify_baselines_host(outdir: Path, bmetrics: dict, ds: Dataset, inputs: dict) -> dict:
    """Run the float IK's C on the host: its delivered error is measured against the exact IK
    (libm is not bit-reproducible, so there is no integer model to match)."""
    from nnik.targets.host import run_host_driver

    model = TrainedModel.load(outdir / MODEL_FILE)
    scn = model.scenario
    c_dir = outdir / C_DIR
    if bmetrics["float"]["available"]:
        test_um = inputs["test"]
        c = run_host_driver(c_dir, f"{scn.name}_float", test_um, libs=("-lm",))
        truth = _truth_for_um(scn, test_um, ds.q["test"])
        bmetrics["float"].update(error_stats(c["out"], truth))
    return bmetrics


def verify(outdir: Path, target: str = "host"):
    """Run the generated C on a target and compare it bit for bit with the integer model."""
    from nnik.implementations.mlp.host import verification_inputs, verify_host

    if target in TARGET_OPTS:
        return verify_target(outdir, target)
    if target != "host":
        raise NnikError(f"unknown target {target!r} (host, avr, pic18)")
    im, alt_im = export(outdir)  # deterministic: regenerates the same C and integer models
    ds = Dataset.load(outdir / DATA_FILE)
    inputs = verification_inputs(im, ds.p["test"])
    res = verify_host(im, outdir / MLP_DIR, inputs)
    res["other_kernel"] = {"kernel": alt_im.kernel,
                           **verify_host(alt_im, outdir / MLP_DIR / alt_im.kernel, {"test": inputs["test"]})}
    res["bit_exact"] = res["bit_exact"] and res["other_kernel"]["bit_exact"]
    res["c_hash"] = dir_hash(outdir / MLP_DIR, im.name)
    metrics = load_metrics(outdir)
    metrics["host"] = res
    metrics["baselines"] = _verify_baselines_host(outdir, metrics["baselines"], ds, inputs)
    write_metrics(outdir, metrics, merge=False)
    return res



# ---- simulated targets ------------------------------------------------------------------------
TARGET_OPTS = {"avr": ("-Os", "-O2"), "pic18": ("",)}


def target_vectors(im, p_test_mm: np.ndarray, n_test: int = 200) -> np.ndarray:
    """A few hundred vectors: test points, the domain's corners and edges, out-of-domain points."""
    lo, hi = im.inp.lo, im.inp.hi
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]], dtype=np.int64)
    mid = (lo + hi) // 2
    edges = np.array([[mid[0], lo[1]], [mid[0], hi[1]], [lo[0], mid[1]], [hi[0], mid[1]], mid], dtype=np.int64)
    span = hi - lo
    outside = np.array([[lo[0] - 1, mid[1]], [hi[0] + 1, mid[1]], [mid[0], lo[1] - span[1]], [mid[0], hi[1] + span[1]],
                        [lo[0] - span[0], lo[1] - span[1]], [hi[0] + span[0], hi[1] + span[1]],
                        [-(2**31), 2**31 - 1], [2**31 - 1, -(2**31)]], dtype=np.int64)
    test = np.rint(p_test_mm[:n_test] * 1000).astype(np.int64)
    return np.concatenate([test, corners, edges, outside])


def _target_row(res: dict, truth_in: np.ndarray | None, out: np.ndarray, inside: np.ndarray) -> dict:
    row = {"cycles": float(res["cycles_mean"]), "cycles_max": int(res["cycles_max"]),
           "flash_bytes": int(res["model_flash_bytes"]), "ram_bytes": int(res["model_ram_bytes"]),
           "program_flash_bytes": int(res["flash_bytes"]), "program_ram_bytes": int(res["ram_bytes"]),
           "compiler": res["compiler"], "flags": res["compiler_flags"], "us": float(res["us_mean"])}
    if truth_in is not None:
        row["max_abs"] = np.abs(out[inside] - truth_in).max(0).tolist()
    return row


def estimate_row(im, target: str, measured: dict | None = None) -> dict:
    """The static estimator's prediction, and its % difference from a measurement if given."""
    from nnik.implementations.mlp.cost import estimate

    e = estimate(im, target)
    row = {k: e[k] for k in ("cycles", "flash_bytes", "ram_bytes", "profile", "validated", "cycles_error_pct") if k in e}
    if measured:
        row["cycles_error_pct"] = 100 * (e["cycles"] - measured["cycles"]) / measured["cycles"]
        row["flash_error_pct"] = 100 * (e["flash_bytes"] - measured["flash_bytes"]) / max(measured["flash_bytes"], 1)
    return row


def verify_target(outdir: Path, target: str) -> dict:
    """Run the MLP (each compiler setting) and the float IK in the same harness."""
    from nnik.targets import TargetError, available, run_on_target

    ok, reason = available(target)
    if not ok:
        res = {"not_run": reason}
        write_metrics(outdir, {"targets": {**load_metrics(outdir).get("targets", {}), target: res}})
        return res
    im, alt_im = export(outdir)
    ds = Dataset.load(outdir / DATA_FILE)
    metrics = load_metrics(outdir)
    scn = TrainedModel.load(outdir / MODEL_FILE).scenario
    c_dir = outdir / C_DIR
    vec = target_vectors(im, ds.p["test"])
    inside = np.all((vec >= im.inp.lo) & (vec <= im.inp.hi), axis=1)
    n_in = int(inside.sum())
    truth = _truth_for_um(scn, vec[inside], ds.q["test"][:n_in]) if scn.mechanism.analytic else None
    _, want, want_flags = im.run(vec)

    def run(prefix, opt, src_dir=c_dir, tag=""):
        try:
            return run_on_target(target=target, sources=[src_dir / f"{prefix}.c"], include_dirs=[src_dir], name=prefix,
                                 vectors=vec, opt=opt or "-Os",
                                 workdir=(outdir / "targets" / target / (prefix + tag + opt)).resolve())
        except TargetError as exc:
            raise NnikError(f"{target}: {exc}") from None

    kernels, mismatches = {}, 0
    alt = alt_im.kernel
    _, alt_want, alt_flags = alt_im.run(vec)
    mlp_dir = outdir / MLP_DIR
    runs = [(im.kernel, opt, mlp_dir, want, want_flags) for opt in TARGET_OPTS[target]]
    runs.append((alt, TARGET_OPTS[target][0], mlp_dir / alt, alt_want, alt_flags))
    for kernel, opt, src_dir, w, wf in runs:
        r = run(scn.name, opt, src_dir, kernel)
        bad = np.any(r["outputs"] != w, axis=1) | (r["flags"] != wf)
        mismatches += int(bad.sum())
        kernels[f"{kernel} {opt}".strip()] = {**_target_row(r, truth, r["outputs"], inside), "mismatches": int(bad.sum()),
                                              "bit_exact": not bad.any()}
    main = kernels[f"{im.kernel} {TARGET_OPTS[target][0]}".strip()]
    base = {}
    if metrics["baselines"]["float"]["available"]:
        r = run(f"{scn.name}_float", TARGET_OPTS[target][0])
        base["float"] = _target_row(r, truth, r["outputs"], inside)
    else:
        base["float"] = {"not_run": metrics["baselines"]["float"]["reason"]}
    # each MLP kernel's own row says whether it is bit-exact
    res = {**main, "kernel": im.kernel, "bit_exact": mismatches == 0, "mismatches": mismatches, "points": int(len(vec)),
           "clock_hz": 16_000_000, "kernels": kernels, "baselines": base}
    if "cycles" in base["float"]:
        res["speedup_vs_float"] = base["float"]["cycles"] / main["cycles"]
    res["estimate"] = estimate_row(im, target, main)
    res["c_hash"] = dir_hash(outdir / MLP_DIR, im.name)
    write_metrics(outdir, {"targets": {**metrics.get("targets", {}), target: res}})
    return res

