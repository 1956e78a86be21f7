"""The estimate: predicted cycles, time, flash and RAM of a model's C on a compiler profile."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.mlp.cost.fast_features import fast_path
from nnik.implementations.mlp.cost.features import (cycle_features, flash_features, is_far, predict_frame, ram_features,
                                                    size_features)
from nnik.implementations.mlp.cost.kernels import kernel_key, model_kernel
from nnik.implementations.mlp.cost.calibrations import (CLOCKS_PER_CYCLE, GOAL_CYCLES_PCT, GOAL_FLASH_PCT,
                                                        load_calibration, resolve_profile)
from nnik.implementations.mlp.cost.shifts import shift_offset
from nnik.implementations.mlp.cost.span import outside_span, structure_row
from nnik.implementations.mlp.cost.structure import structure
from nnik.implementations.mlp.cost.trace import typical_inputs
from nnik.implementations.mlp.cost.validity import reference_c_hash, stored_hash


BREAKDOWN_GROUPS = (
    ("call + input stage", ("call", "input_k0", "input_neg", "multi_layer")),
    ("MAC layer 1 (operand signs, int8)", ("mac_first", "mac_first_w8", "mac_first_", "mac_first_w8_")),
    ("MAC hidden-to-hidden", ("mac_hidden", "mac_hidden_w8", "mac_hidden_", "mac_hidden_w8_", "mac_hidden_bigtab")),
    ("MAC output (operand signs, int8)", ("mac_out", "mac_out_w8", "mac_out_", "mac_out_w8_")),
    ("hidden neuron (bias, layer-1 and output MACs, loop, tanh)", ("tanh[", "tanh_call[", "tanh_class[",
                                                                  "tanh_dead[", "neuron_deep", "far_neuron", "far_residual_neuron")),
    ("tanh input clamp", ("sat_clamp", "sat_hit")),
    ("output conversion", ("output", "output_e_pos", "output_e_neg")),
    ("residual affine", ("affine_term", "affine_mul[", "affine_neg", "residual")),
    ("residual: register pressure", ("residual_neuron", "residual_neuron_deep")),
    ("DAC clamp", ("dac_clamp", "dac_hit")),
)


def _group_of(name: str) -> str:
    if ":" in name.split("[", 1)[0]:  # a fast-kernel feature, prefixed by its code path
        name = name.split(":", 1)[1]
        if name.startswith(("mac_first_u", "mac_hidden_u", "mac_out_u", "mac_hidden_loop", "mac_out_loop",
                            "loop_neuron")):
            return {"mac_f": "MAC layer 1", "mac_h": "MAC hidden-to-hidden", "mac_o": "MAC output"}.get(
                name[:5], "MAC hidden-to-hidden")
        if name.startswith(("neuron_", "t_", "far_neuron", "tanh", "sat_")):
            return "hidden neuron (start, shift, tanh)"
        if name.startswith("out_"):
            return "output conversion"
        if name.startswith("input_"):
            return "call + input stage"
    for g, keys in BREAKDOWN_GROUPS:
        for k in keys:
            if name == k or (k.endswith(("[", "_")) and name.startswith(k)):
                return g
    return "other"


def estimate(im, target: str, profile: str | None = None, clock_hz: int = 16_000_000, *,
             kernel: str | None = None, inputs_um: np.ndarray | None = None) -> dict:
    """Predicted cycles per IK call (mean over typical inputs), time, flash and RAM of the
    generated C for `im` on `target` ("avr" | "pic18") with a compiler profile (default: the
    target's; see profiles()).

    Returns {cycles, us, flash_bytes, ram_bytes, profile, target, kernel, validated, breakdown,
    notes}. `us` uses clock_hz (PIC18: 4 clocks per instruction cycle). `validated` is True when
    the profile was calibrated on a simulator, the emitted C is unchanged since (validity), and every
    primitive the model uses was part of the calibration (1-2 hidden layers)."""
    prof = resolve_profile(target, profile)
    cal = load_calibration(prof)
    if clock_hz <= 0:
        raise NnikError(f"clock_hz must be > 0, got {clock_hz}")
    kern = model_kernel(im, kernel)
    kkey = kernel_key(kern)
    kernels = cal.get("kernels", {})
    if kkey not in kernels:
        if len(kernels) == 1 and kern is None:
            kkey = next(iter(kernels))
        else:
            raise NnikError(f"profile {prof!r} has no calibration for kernel {kkey!r} "
                            f"(calibrated: {', '.join(kernels) or 'none'}); re-run calibrate")
    kc = kernels[kkey]
    notes: list[str] = []
    V = im.tanh_variant
    if kern != "fast" and f"tanh[{V}]" not in kc["cycles"]["coef"]:
        raise NnikError(f"tanh variant {V!r} is not calibrated for profile {prof!r} "
                        f"(calibrated: {', '.join(kc.get('variants', []))}); re-run calibrate")
    pts = typical_inputs(im) if inputs_um is None else np.asarray(inputs_um, dtype=np.int64)
    frame = predict_frame(im, kc.get("frame"))
    far = is_far(frame, kc.get("frame"))
    feats = {k: float(np.mean(v)) for k, v in cycle_features(im, pts, far=far, target=cal["target"]).items()}
    coef = kc["cycles"]["coef"]
    missing = [k for k, v in feats.items() if k not in coef and v != 0]
    if missing:
        notes.append(f"primitives not in the calibration (counted as 0): {', '.join(missing)}")
    breakdown: dict[str, float] = {}
    cycles = 0.0
    for k, v in feats.items():
        c = coef.get(k, 0.0) * v
        cycles += c
        g = _group_of(k)
        breakdown[g] = breakdown.get(g, 0.0) + c
    if kern != "fast":  # the portable C shifts by constants; the fast kernel's shifts are features
        sh_total, sh_per = shift_offset(im, cal["shift_tables"], "cycles")
        cycles += sh_total
        for place, val in sh_per.items():
            breakdown[f"shifts ({place})"] = val

    sf = size_features(im, far=far, target=cal["target"])
    flash_coef, ram_coef = kc["flash"]["coef"], kc["ram"]["coef"]
    flash = sum(flash_coef.get(k, 0.0) * v for k, v in flash_features(sf).items())
    if kern != "fast":
        fl_sh, _ = shift_offset(im, cal["shift_tables"], "bytes")
        flash += fl_sh
    ram = sum(ram_coef.get(k, 0.0) * v for k, v in ram_features(sf).items())
    fmissing = [k for k, v in flash_features(sf).items() if k not in flash_coef and v != 0]
    if fmissing:
        notes.append(f"flash features not in the calibration: {', '.join(fmissing)}")
    s = structure(im)
    validated = bool(cal.get("validated", False))
    if not validated:
        notes.append(f"profile {prof!r} is an extrapolation, not calibrated on a simulator")
    if stored_hash(cal, kkey) != reference_c_hash(kern):
        validated = False
        notes.append("the emitted C changed since this calibration (the C of its reference models differs): re-run "
                     f"`python3 -m nnik.bench.mlp_cost calibrate --target {cal['target']}`")
    if s["layers"] > 2:
        validated = False
        notes.append("more than two hidden layers: extrapolated (calibrated on 1-2)")
    if min(s["H"]) < 3 or s["n_in"] != 2 or s["n_out"] != 2:
        validated = False
        notes.append("outside the calibrated shapes (2 inputs, 2 outputs, hidden sizes >= 3)")
    env = kc.get("envelope", {})
    if kern == "fast":
        path = fast_path(im, cal["target"])
        big = env.get(f"{path}:{s['layers']}")
        if big is None or max(s["H"]) > big:
            validated = False
            notes.append(f"the fast kernel's {path} code with {s['layers']} hidden layer(s) was calibrated on hidden "
                         f"sizes up to {big or 0} only")
    if kern == "fast" and "span_rows" in kc:
        off = outside_span(structure_row(im, far, cal["target"]), kc["span_rows"])
        if off:
            validated = False
            notes.append("a combination of counts no calibration network had (extrapolated): " + ", ".join(off))
    if missing or fmissing:
        validated = False
    # the last recorded sweep of this profile and kernel, for networks with as many layers
    val = (cal.get("validation") or {}).get(kkey, {})
    vl = val.get("by_layers", {}).get(str(s["layers"])) if isinstance(val, dict) else None
    if vl is None:
        validated = False
        notes.append(f"no recorded sweep for {s['layers']}-layer networks (python3 -m nnik.bench.mlp_cost sweep --record"
                     + ("" if kern in (None, "portable") else f" --kernel {kern}") + ")")
    elif vl["max_abs_cycles_err_pct"] > GOAL_CYCLES_PCT or vl["max_abs_flash_err_pct"] > GOAL_FLASH_PCT:
        validated = False
        notes.append(f"the recorded sweep of {s['layers']}-layer networks missed the goals: cycles within "
                     f"{vl['max_abs_cycles_err_pct']:.1f} %, flash within {vl['max_abs_flash_err_pct']:.1f} %")
    else:
        notes.append(f"recorded sweep, {s['layers']}-layer networks: cycles within {vl['max_abs_cycles_err_pct']:.2f} %, "
                     f"flash within {vl['max_abs_flash_err_pct']:.2f} % ({vl['networks']} networks)")
    stated = stated_cycles_error_pct(cal, kkey, vl) if validated else None
    if stated is not None:
        notes.append(f"stated cycle error: within ±{stated:g} % (measured: the larger of the recorded sweep's worst "
                     "and, for the fast kernel, the search-space check's worst error plus a margin)")
    cpc = CLOCKS_PER_CYCLE[cal["target"]]
    return {
        "cycles": float(cycles),
        "us": float(cycles) * cpc / clock_hz * 1e6,
        "flash_bytes": round(flash),
        "ram_bytes": round(max(ram, 0.0)),
        "profile": prof,
        "target": cal["target"],
        "compiler": cal.get("compiler", ""),
        "kernel": kern,
        "clock_hz": int(clock_hz),
        "validated": validated,
        "cycles_error_pct": stated,
        "breakdown": {k: round(v, 1) for k, v in breakdown.items() if abs(v) > 1e-9},
        "notes": notes,
    }


def stated_cycles_error_pct(cal: dict, kkey: str, sweep_by_layers: dict | None) -> float | None:
    """What a validated estimate states about its cycle error, in %: the measured band, i.e. the
    larger of the recorded sweep's worst for networks with as many layers and, for the fast
    kernel, the search-space check's band (random architectures the search can propose, residual
    ones too; see nnik.bench.mlp_cost.search_check).  None when nothing was measured."""
    bounds = []
    if sweep_by_layers:
        bounds.append(float(sweep_by_layers["max_abs_cycles_err_pct"]))
    sc = (cal.get("search_check") or {}).get(kkey)
    if isinstance(sc, dict) and "stated_cycles_err_pct" in sc:
        bounds.append(float(sc["stated_cycles_err_pct"]))
    return max(bounds) if bounds else None


def format_estimate(est: dict, im=None) -> str:
    shape = "-".join(map(str, im.shape)) + f", tanh {im.tanh_variant}" if im is not None else ""
    unit = "instruction cycles" if est["target"] == "pic18" else "cycles"
    lines = [f"{shape}  on {est['profile']} ({est['compiler']}), kernel {est['kernel'] or 'default'}".strip(),
             f"  {est['cycles']:.0f} {unit} per call = {est['us']:.1f} us at {est['clock_hz'] / 1e6:g} MHz",
             f"  flash {est['flash_bytes']} B, RAM {est['ram_bytes']} B static"
             + (" (the network's arrays live on the stack)" if est["target"] == "avr" else ""),
             f"  validated: {'yes' if est['validated'] else 'no'}"]
    for k, v in sorted(est["breakdown"].items(), key=lambda kv: -abs(kv[1])):
        lines.append(f"    {k:34s} {v:9.0f}")
    for n in est["notes"]:
        lines.append(f"  note: {n}")
    return "\n".join(lines)


def load_integer_model(path: Path, tanh: str | None = None, weight_bits: int | None = None,
                       kernel: str | None = None):
    """The IntegerModel of a trained model: OUTDIR (with model.pt, data.npz) or a model.pt,
    quantised as `nnik` exports it (the scenario's [export] tanh, weight_bits and kernel)."""
    from nnik.implementations.mlp import quantize as fx
    from nnik.machine.data import Dataset
    from nnik.implementations.mlp.train import TrainedModel

    path = Path(path)
    mp = path / "model.pt" if path.is_dir() else path
    model = TrainedModel.load(mp)
    scn = model.scenario
    if tanh is None:
        tanh = None if scn.export.get("tanh", "default") == "default" else scn.export["tanh"]
    wb = weight_bits or scn.export.get("weight_bits", 16)
    calib = None
    dp = mp.parent / "data.npz"
    if dp.is_file():
        ds = Dataset.load(dp)
        calib = fx.calibration_set(model, ds.p["train"], ds.q["train"])
    kernel = kernel or scn.export.get("kernel")
    return fx.quantize(model, tanh_variant=tanh, weight_bits=wb, calib=calib, kernel=kernel or None)
