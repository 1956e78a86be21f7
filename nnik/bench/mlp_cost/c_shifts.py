"""The AVR C path's constant shifts, priced by what the compiler emits (a calibration step).

The one-layer C path of the fast kernel shifts every tanh input by sh (nnik_tu_shr), the layer-1
inputs by K (nnik_shr24_16) and the outputs by F, e and the affine base's P and G - P (nnik_out_shr,
int32 shifts).  The network fit priced each shift regime as a + b * n, with b fitted from networks
whose n barely varies (the search's int16 networks have sh 16-19, the galvo's K is 2): on
avr-gcc -O2 it put b at -3.0 cycles per bit of sh above 16, -38.7 per bit of K and +31.8 per bit of
a plain output's F in 17-23, where the code is an asr/ror pair (2 cycles) per bit, a 6-cycle and a
7-cycle loop step; and it gave the output exponent's regimes constants of -58 to -155 cycles an
output where the code adds a constant (3 cycles besides the shift).  A network with sh 18 came out
5 cycles a neuron short (the search check's worst, galvo 2-10-2 lerp_mr, -2.75 %); fresh draws
missed by -3.7 % (galvo 2-3-2 lerp32 int8) and -3.5 % (dual 2-6-2 lerp_mr4 int8, e = 1).

Here the per-bit costs are measured (the kernel primitives on the simulator: the shift alone by two
amounts of its regime, net of the same harness; the int32 shifts from the profile's shift tables;
what a non-zero output exponent adds, whole), kept fixed, and the C path's other coefficients are re-fitted to the calibration networks'
recorded cycles (their means: the data-dependent coefficients, the tanh classes and the clamp
hits, and the tanh replacements' calls, which the two-layer C path shares, keep the values the
full fit gave them).  A full calibration keeps the same slopes fixed (calibrate._c_shift_slopes).

    python3 -m nnik.bench.mlp_cost.c_shifts --profile avr-gcc-O2 [--write]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from nnik.implementations.mlp.cost.calibrations import CAL_DIR, REPO_ROOT, cal_path, forget_loaded

WORK_DIR = REPO_ROOT / "build" / "estimator_c_shifts"
# feature -> where its cost per bit is measured: the profile's shift tables (int32 shifts by a
# constant, nnik.bench.mlp_cost.measure.measure_shift_tables: "as" x >> n, "sl" x * 2^n) or the
# kernel primitive itself on the simulator (a C expression of the shift by {n}); and two amounts
# of its regime between which the code is the same loop or unrolled step
# the output's exponent e (fastc._output_lines): total = C + (acc >> e), or C + acc * 2^-e, where
# e = 0 takes acc as it is; what e != 0 adds over that is measured whole (the regime's count
# feature gets the part that does not grow with e, INTERCEPTS)
_E_POS = "(int32_t)0x12345678L + nnik_sar32((int32_t)a, {n})"
_E_NEG = "(int32_t)0x12345678L + (int32_t)a * (int32_t)(1L << {n})"
INTERCEPTS = {"c:out_e_pos_n[1_7]": "c:out_e_pos[1_7]", "c:out_e_pos_n[8_15]": "c:out_e_pos[8_15]",
              "c:out_e_neg_n[1_7]": "c:out_e_neg[1_7]"}
SLOPES = {"c:t_sh_n[8_14]": ("nnik_tu_shr(a, {n})", (8, 14)),
          "c:t_sh_n[17_23]": ("nnik_tu_shr(a, {n})", (17, 21)),
          "c:out_foldF_n[17_23]": ("nnik_out_shr(a, {n})", (17, 23)),
          "c:out_foldF_n[24_31]": ("nnik_out_shr(a, {n})", (25, 31)),
          "c:input_k_n[1_7]": ("nnik_shr24_16(a, {n})", (1, 7)),
          "c:out_F_n[8_15]": ("as", (9, 15)), "c:out_F_n[17_23]": ("as", (17, 23)),
          "c:out_F_n[24_31]": ("as", (25, 30)),
          "c:out_e_pos_n[1_7]": (_E_POS, (3, 7)), "c:out_e_pos_n[8_15]": (_E_POS, (9, 15)),
          "c:out_e_pos_n[16_23]": ("as", (17, 23)),
          "c:out_e_neg_n[1_7]": (_E_NEG, (3, 7)), "c:out_e_neg_n[8_15]": ("sl", (9, 15)),
          "c:aff_p_n[1_7]": ("as", (3, 7)), "c:aff_p_n[8_15]": ("as", (9, 15)), "c:aff_p_n[16_23]": ("as", (17, 23)),
          "c:aff_gp_n[1_7]": ("as", (3, 7)), "c:aff_gp_n[8_15]": ("as", (9, 15)),
          "c:aff_gp_n[16_23]": ("as", (17, 23))}
# kept as the full fit gave them: the coefficients fitted from how the calibration networks' inputs
# spread (not from their means), and the called tanh replacements' costs, which the two-layer C
# path (c2call) prices with the same keys (fast_features._feature_key)
KEPT = ("tanh_class[", "sat_hit", "dac_hit", "tanh[")
_HEADER = ("#include <stdint.h>\n#define NNIK_TB_N_IN 2\n#define NNIK_TB_N_OUT 2\n"
           "int8_t nnik_tb_ik(const int32_t in_um[2], int32_t out[2]);\n")
_BODY = ("\nint8_t nnik_tb_ik(const int32_t in_um[2], int32_t out[2])\n{{\n"
         "    uint32_t a = (uint32_t)in_um[0];\n"
         "    out[0] = in_um[1] ? (int32_t){expr} : (int32_t)a;\n    out[1] = 0;\n    return 0;\n}}\n")


def measure_slopes(profile: str, workdir: Path = WORK_DIR, tables: dict | None = None) -> dict[str, float]:
    """{feature: cycles per bit} of each shift of SLOPES on this profile, and the intercepts of
    INTERCEPTS (tables: the profile's
    shift tables' cycles; default: those of its calibration file)."""
    from nnik.bench.mlp_cost.measure import run_profile
    from nnik.implementations.mlp.cost.kernels import write_c
    from nnik.implementations.mlp.cost.synthetic import CalSpec, synthetic_model

    if tables is None:
        tables = json.loads(cal_path(profile).read_text())["shift_tables"]["cycles"]
    probe = write_c(synthetic_model(CalSpec("galvo", (3,), seed=1, gain=0.3), kernel="fast"), workdir / "probe",
                    kernel="fast").parent
    rng = np.random.default_rng(5)
    x = rng.integers(0, 2**24, 16)  # nnik_shr24_16 takes 24 bits; the others cost the same for any x
    vec = np.stack([np.concatenate([x, x]), np.concatenate([np.ones(16), np.zeros(16)])], 1).astype(np.int64)
    out = {}
    for feat, (src, (lo, hi)) in SLOPES.items():
        if src in tables:
            out[feat] = round(float((tables[src][hi] - tables[src][lo]) / (hi - lo)), 3)
            continue
        net = []
        for n in (lo, hi):
            d = workdir / profile / f"{src.split('(')[0]}{n}"
            d.mkdir(parents=True, exist_ok=True)
            for h in ("nnik_flash.h", "nnik_kernel.h"):
                (d / h).write_text((probe / h).read_text())
            (d / "nnik_tb.h").write_text(_HEADER)
            (d / "nnik_tb.c").write_text('#include <stdint.h>\n#include "nnik_flash.h"\n#include "nnik_kernel.h"\n'
                                         '#include "nnik_tb.h"\n' + _BODY.format(expr=src.format(n=n)))
            cyc = run_profile(profile, d / "nnik_tb.c", "nnik_tb", vec, 2, d / "w")["cycles"].astype(float)
            net.append(cyc[:16].mean() - cyc[16:].mean())
        out[feat] = round(float((net[1] - net[0]) / (hi - lo)), 3)
        if feat in INTERCEPTS:
            out[INTERCEPTS[feat]] = round(float(net[0] - out[feat] * lo), 3)
    return out


def _network_rows(kc: dict) -> tuple[list[dict], np.ndarray, list[str]]:
    """Mean cycle features and recorded mean cycles of the calibration networks on the one-layer C path."""
    from nnik.implementations.mlp.cost.fast_features import cycle_prefix
    from nnik.implementations.mlp.cost.features import cycle_features
    from nnik.implementations.mlp.cost.fit import FAR_ABOVE
    from nnik.implementations.mlp.cost.synthetic import calibration_specs, in_domain_vectors, synthetic_model

    specs = {sp.label: sp for sp in calibration_specs("fast", target="avr")}
    rows, y, labels = [], [], []
    for m in kc["models"]:
        sp = specs.get(m["spec"])
        if sp is None:
            continue
        im = synthetic_model(sp, kernel="fast")
        if cycle_prefix(im, "avr") != "c":
            continue
        vec = in_domain_vectors(im, sp.n_vec, seed=sp.seed + 7)
        far = m.get("frame") is not None and m["frame"] > FAR_ABOVE
        rows.append({k: float(np.mean(v)) for k, v in cycle_features(im, vec, far=far, target="avr").items()})
        y.append(float(m["cycles_mean"]))
        labels.append(m["spec"])
    return rows, np.array(y), labels


def refit(profile: str, slopes: dict[str, float]) -> tuple[dict, dict]:
    """The profile's fast-kernel cycle coefficients with the C path's shift slopes fixed and its
    other coefficients re-fitted; and a summary of the fit."""
    from nnik.implementations.mlp.cost.fit import lstsq

    cal = json.loads(cal_path(profile).read_text())
    kc = cal["kernels"]["fast"]
    coef = dict(kc["cycles"]["coef"])
    rows, y, labels = _network_rows(kc)
    before = np.array([sum(coef.get(k, 0.0) * v for k, v in r.items()) for r in rows])
    fixed = {k: v for k, v in coef.items() if not k.startswith("c:") or any(s in k for s in KEPT)}
    fixed.update(slopes)
    free_rows = [{k: v for k, v in r.items() if k not in fixed} for r in rows]
    offset = np.array([sum(fixed.get(k, 0.0) * v for k, v in r.items() if k in fixed) for r in rows])
    new, fit = lstsq(free_rows, y, offset)
    pred = fit.pop("pred")
    out = {**{k: v for k, v in coef.items() if not k.startswith("c:")}, **{k: v for k, v in coef.items() if k in fixed},
           **{k: round(v, 4) for k, v in new.items()}, **slopes}
    err_b, err_a = 100 * (before - y) / y, 100 * (pred - y) / y
    return dict(sorted(out.items())), {
        "networks": len(y), "slopes": slopes,
        "before_pct": [round(float(err_b.min()), 2), round(float(err_b.max()), 2)],
        "after_pct": [round(float(err_a.min()), 2), round(float(err_a.max()), 2)],
        "worst": labels[int(np.argmax(np.abs(err_a)))]}


def write(profile: str, coef: dict, summary: dict) -> None:
    path = cal_path(profile)
    cal = json.loads(path.read_text())
    kc = cal["kernels"]["fast"]
    kc["cycles"]["coef"] = coef
    # a full calibration keeps these slopes fixed too (calibrate._c_shift_slopes)
    kc["c_shifts"] = {**summary, "command": f"python3 -m nnik.bench.mlp_cost.c_shifts --profile {profile} --write"}
    path.write_text(json.dumps(cal, indent=1) + "\n")
    forget_loaded()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m nnik.bench.mlp_cost.c_shifts", description=__doc__.split("\n\n")[0])
    ap.add_argument("--profile", default="avr-gcc-O2", choices=sorted(p.stem for p in CAL_DIR.glob("avr-*.json")))
    ap.add_argument("--write", action="store_true", help="store the coefficients in the calibration file")
    a = ap.parse_args(argv)
    slopes = measure_slopes(a.profile)
    coef, summ = refit(a.profile, slopes)
    print(json.dumps(summ, indent=1))
    if a.write:
        write(a.profile, coef, summ)
    return 0


if __name__ == "__main__":
    sys.exit(main())
