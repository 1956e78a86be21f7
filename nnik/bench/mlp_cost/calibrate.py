"""Calibration, a developer tool: microbenchmarks on the simulators, fitted into
nnik/calibration/<profile>.json (``python3 -m nnik.bench.mlp_cost calibrate``)."""

from __future__ import annotations

import datetime
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from nnik.errors import NnikError
from nnik.implementations.mlp.cost.fit import fit_measurements
from nnik.implementations.mlp.cost.sdcc_c import tanh_coefs
from nnik.implementations.mlp.cost.kernels import kernel_key, kernel_options
from nnik.bench.mlp_cost.measure import measure_kernel, measure_shift_tables
from nnik.implementations.mlp.cost.calibrations import (BUILTIN_PROFILES, CAL_DIR, CALIBRATION_FORMAT, DEFAULT_PROFILE,
                                                        REPO_ROOT, cal_path, forget_loaded, resolve_profile)
from nnik.implementations.mlp.cost.trace import TYPICAL_N, TYPICAL_SEED
from nnik.implementations.mlp.cost.validity import reference_c_hash, stored_hash

CAL_WORK_DIR = REPO_ROOT / "build" / "estimator_calibration"


def calibrate(target: str, profile: str | None = None, *, kernels: Sequence[str | None] | None = None,
              workdir: Path | None = None, write: bool = True, verbose: bool = True, refit: bool = False) -> dict:
    """Run the microbenchmarks for one profile (default: the target's default profile) and write
    nnik/calibration/<profile>.json.  Returns the calibration dict.

    refit=True re-fits the measurements kept by the last run under build/estimator_calibration
    (no simulator; for work on the cost model itself)."""
    from nnik.targets import available
    from nnik.targets.toolchain import tool_version

    prof = resolve_profile(target, profile)
    if prof not in BUILTIN_PROFILES:
        raise NnikError(f"profile {prof!r} cannot be calibrated here (no simulator for it)")
    ok, why = available(target)
    if not ok and not refit:
        raise NnikError(f"cannot calibrate {prof}: {why}")
    t0 = time.perf_counter()
    p = BUILTIN_PROFILES[prof]
    wd = Path(workdir or CAL_WORK_DIR) / prof
    say = (lambda m: print(m, file=sys.stderr, flush=True)) if verbose else (lambda m: None)
    kernels = list(kernels) if kernels is not None else kernel_options()
    tables = None
    if not refit:
        say(f"[{prof}] shift microbenchmark")
        tables = measure_shift_tables(prof, wd)
    out_kernels = {}
    compiler, flags = "", ""
    for kern in kernels:
        kkey = kernel_key(kern)
        try:
            if refit:
                out_kernels[kkey], compiler, flags, tables = _refit_kernel(prof, kern, wd, say)
                continue
            tk = time.perf_counter()
            out_kernels[kkey], compiler, flags = _calibrate_kernel(prof, kern, tables, wd, say)
            out_kernels[kkey]["seconds"] = round(time.perf_counter() - tk, 1)
        except NnikError as exc:
            if len(kernels) == 1:
                raise
            say(f"[{prof}/{kkey}] skipped: {exc}")
    if not out_kernels:
        raise NnikError(f"{prof}: no kernel could be calibrated")
    seconds = time.perf_counter() - t0
    prev: dict = {}
    if cal_path(prof).is_file():
        try:
            prev = json.loads(cal_path(prof).read_text())
        except (OSError, json.JSONDecodeError):
            prev = {}
    for kkey, kc in out_kernels.items():
        if refit and kkey in prev.get("kernels", {}):
            kc["reference_c_hash"] = stored_hash(prev, kkey)  # that of the measurements
        kc.setdefault("reference_c_hash", reference_c_hash(kc["kernel"]))
        if refit and kkey in prev.get("kernels", {}):
            kc["seconds"] = prev["kernels"][kkey].get("seconds")
            kc["date"] = prev["kernels"][kkey].get("date")
        else:
            kc["date"] = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    if prev.get("format") == CALIBRATION_FORMAT:  # keep the kernels this run did not calibrate
        for kkey, kc in prev.get("kernels", {}).items():
            out_kernels.setdefault(kkey, kc)
    cal = {
        "format": CALIBRATION_FORMAT,
        "profile": prof,
        "target": p["target"],
        "description": p["description"],
        "compiler": compiler or tool_version(p["compiler"] if p["compiler"] != "avr-gcc" else "avr-gcc"),
        "flags": flags,
        "validated": True,
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "command": f"python3 -m nnik.bench.mlp_cost calibrate --target {p['target']}" + (
            f" --profile {prof}" if prof != DEFAULT_PROFILE[p["target"]] else ""),
        "seconds": round(seconds, 1) if not refit else prev.get("seconds"),
        "validity": "an estimate is validated while kernels/*/reference_c_hash equals the hash of the C emitted "
                    "today for the reference models (nnik.implementations.mlp.cost.validity)",
        "typical_inputs": f"{TYPICAL_N} uniform points of the trained domain (seed {TYPICAL_SEED})",
        "shift_tables": tables,
        "kernels": out_kernels,
    }
    if write:
        old = cal_path(prof)
        # a recorded sweep still stands for the kernels whose emitted C is unchanged
        kept = {k: v for k, v in (prev.get("validation") or {}).items()
                if k in out_kernels and (refit or stored_hash(prev, k) == stored_hash(cal, k))}
        if kept:
            cal["validation"] = kept
        CAL_DIR.mkdir(parents=True, exist_ok=True)
        old.write_text(json.dumps(cal, indent=1) + "\n")
        forget_loaded()
        say(f"[{prof}] wrote {old} in {seconds:.0f} s")
    return cal


def _tanh_bench(prof: str, kern: str | None, meas: list[dict], wd: Path, say) -> dict:
    """PIC18's fast kernel: the tanh replacements its C path calls, measured per input class
    (nnik.bench.mlp_cost.tanh_bench); {} elsewhere (their classes are fitted with the networks)."""
    from nnik.bench.mlp_cost.tanh_bench import measure_tanh_classes
    from nnik.implementations.mlp.cost.fast_features import fast_path

    if kern != "fast" or BUILTIN_PROFILES[prof]["target"] != "pic18":
        return {}
    variants = sorted({m["im"].tanh_variant for m in meas if fast_path(m["im"], "pic18") == "c"
                       and any(not L.tanh_step for L in m["im"].hidden)})
    say(f"[{prof}/fast] tanh classes of {', '.join(variants)}")
    return measure_tanh_classes(prof, variants, wd / "tanh_bench")


def _c_shift_slopes(prof: str, kern: str | None, tables: dict, wd: Path, say) -> dict[str, float]:
    """AVR's fast kernel: the cycles per bit of the C path's constant shifts, measured
    (nnik.bench.mlp_cost.c_shifts) and kept fixed in the fit; {} elsewhere."""
    if kern != "fast" or BUILTIN_PROFILES[prof]["target"] != "avr":
        return {}
    from nnik.bench.mlp_cost.c_shifts import measure_slopes

    say(f"[{prof}/fast] the C path's shifts, per bit")
    return measure_slopes(prof, wd / "c_shifts", tables["cycles"])


def _refit_kernel(prof: str, kern: str | None, wd: Path, say) -> tuple[dict, str, str, dict]:
    import pickle

    path = wd / kernel_key(kern) / "measurements.pkl"
    if not path.is_file():
        raise NnikError(f"no stored measurements for {prof}/{kernel_key(kern)} (run calibrate without --refit)",
                        str(path))
    blob = pickle.loads(path.read_bytes())
    if "tanh_bench" not in blob:  # measurements kept before the tanh microbenchmark existed
        blob["tanh_bench"] = _tanh_bench(prof, kern, blob["meas"], wd, say)
        path.write_bytes(pickle.dumps(blob))
    slopes = blob.get("c_shifts", {})
    result = fit_measurements(blob["meas"], blob["tables"], kern, {**tanh_coefs(blob["tanh_bench"]), **slopes})
    result["tanh_bench"] = blob["tanh_bench"]
    if slopes:
        result["c_shifts"] = {"slopes": slopes}
    cf = result["cycles"]["fit"]
    say(f"[{prof}/{kernel_key(kern)}] refit: cycles max {cf['max_rel_error_pct']:.2f} % of a network's mean")
    return result, blob["meas"][0]["compiler"], blob["meas"][0]["flags"], blob["tables"]


def _calibrate_kernel(prof: str, kern: str | None, tables: dict, wd: Path, say) -> tuple[dict, str, str]:
    """Measure every calibration network with one kernel and fit cycles, flash and RAM."""
    import pickle

    kkey = kernel_key(kern)
    h0 = reference_c_hash(kern)
    meas = measure_kernel(prof, kern, wd, say)
    bench = _tanh_bench(prof, kern, meas, wd, say)
    slopes = _c_shift_slopes(prof, kern, tables, wd, say)
    reference_c_hash.cache_clear()
    if reference_c_hash(kern) != h0:
        raise NnikError(f"{prof}/{kkey}: the code generator changed during the calibration; run it again")
    try:  # kept for refits while developing the cost model (build/, not package data)
        (wd / kkey).mkdir(parents=True, exist_ok=True)
        (wd / kkey / "measurements.pkl").write_bytes(pickle.dumps({"meas": meas, "tables": tables,
                                                                   "tanh_bench": bench, "c_shifts": slopes}))
    except (OSError, pickle.PicklingError):
        pass
    result = fit_measurements(meas, tables, kern, {**tanh_coefs(bench), **slopes})
    result["tanh_bench"] = bench
    if slopes:
        result["c_shifts"] = {"slopes": slopes}
    result["reference_c_hash"] = h0
    cf, ff, rf = result["cycles"]["fit"], result["flash"]["fit"], result["ram"]["fit"]
    say(f"[{prof}/{kkey}] fit: cycles max residual {cf['max_abs_residual']:.1f} "
        f"(max {cf['max_rel_error_pct']:.2f} % of a network's mean), flash max "
        f"{ff['max_abs_residual']:.1f} B, RAM max {rf['max_abs_residual']:.1f} B")
    return result, meas[0]["compiler"], meas[0]["flags"]
