"""The design space `nnik search` explores: the family and every family's knobs.

Every trial samples every knob of every family (unused ones are ignored), so the search space is
the same for all trials and NSGA-II's crossover works on the knobs too, not only on the family
(Optuna samples parameters outside the common space at random). ``config_of`` maps a trial's
parameters to the family's ``fit(problem, config)`` configuration.
"""

from __future__ import annotations

from nnik.implementations import Problem
from nnik.implementations.lut.family import LutImpl, cell_ladder, k_for_nodes, table_budget
from nnik.implementations.lut.table import dependence
from nnik.implementations.poly.family import MAX_DEGREE

# the families whose knobs this space samples (a new family is searched once its knobs are added here)
SEARCHED = ("mlp", "poly", "lut", "hybrid")
MLP_WIDTHS = (3, 4, 5, 6, 8, 10, 12)
MLP_TANH = ("default", "lerp32", "lerp64", "lerp_mr", "lerp_mr4", "minimax3_x11", "minimax2_x22", "paper_lsq5")
SPLITS = {"none": False, "x": [True, False], "y": [False, True], "both": True}
MIN_NODES = 3


def k_range(span: int, max_nodes: int) -> tuple[int, int]:
    """Cell exponents from `max_nodes` nodes (smallest k) to MIN_NODES nodes (largest k) on `span`."""
    k_hi = k_for_nodes(span, MIN_NODES)
    k_lo = k_hi
    while k_lo > 0 and (span >> (k_lo - 1)) + 2 <= max_nodes:
        k_lo -= 1
    return k_lo, k_hi


def max_nodes(problem: Problem, span: list[int]) -> int:
    """Nodes per axis the ladders reach on this problem: the finest cells of lut.cell_ladder, which
    grows a table to the flash budget of the target and the chip (no fixed node cap)."""
    ks = cell_ladder(span, table_budget(problem), dependence(problem, True))
    return max(MIN_NODES, max((span[a] >> ks[-1][a]) + 2 for a in range(2))) if ks else MIN_NODES


def spans(problem: Problem) -> dict[str, list[int]]:
    """Stored span per axis in input units of the lut and hybrid tables (after the symmetry folds)."""
    span = LutImpl.stored_span(problem)
    return {"lut": span, "hybrid": span}


def suggest(trial, problem: Problem, families: list[str]) -> tuple[str, dict]:
    """Sample the family and every knob; return (family, config)."""
    fam = trial.suggest_categorical("family", list(families))
    p = {}
    p["mlp_depth"] = trial.suggest_int("mlp_depth", 1, 2)
    p["mlp_w1"] = trial.suggest_categorical("mlp_w1", MLP_WIDTHS)
    p["mlp_w2"] = trial.suggest_categorical("mlp_w2", MLP_WIDTHS)
    p["mlp_mode"] = trial.suggest_categorical("mlp_mode", ["full", "residual"])
    p["mlp_tanh"] = trial.suggest_categorical("mlp_tanh", MLP_TANH)
    p["mlp_weight_bits"] = trial.suggest_categorical("mlp_weight_bits", [8, 16])
    p["poly_degree"] = trial.suggest_int("poly_degree", 1, MAX_DEGREE)
    p["poly_coef_bits"] = trial.suggest_categorical("poly_coef_bits", [16, 32])
    p["poly_split"] = trial.suggest_categorical("poly_split", list(SPLITS))
    p["poly_lsb"] = trial.suggest_categorical("poly_lsb", [False, True])
    p["poly_rounding"] = trial.suggest_categorical("poly_rounding", [True, False])
    sp = spans(problem)
    for fam_ in ("lut", "hybrid"):
        nodes = max_nodes(problem, sp[fam_])
        for a, ax in enumerate("xy"):
            lo, hi = k_range(sp[fam_][a], nodes)
            p[f"{fam_}_k{ax}"] = trial.suggest_int(f"{fam_}_k{ax}", lo, hi)
        p[f"{fam_}_W"] = trial.suggest_categorical(f"{fam_}_W", [8, 16])
        p[f"{fam_}_fit"] = trial.suggest_categorical(f"{fam_}_fit", ["lsq", "minimax"])
    p["lut_bits"] = trial.suggest_categorical("lut_bits", [16, 32])
    p["hybrid_coef_bits"] = trial.suggest_categorical("hybrid_coef_bits", [8, 16])
    p["poly_width"] = trial.suggest_categorical("poly_width", [16, 32])  # last: the draws above keep their order
    return fam, config_of(fam, p, problem)


def config_of(fam: str, p: dict, problem: Problem) -> dict:
    """A family's configuration from the sampled knobs (the others are ignored)."""
    if fam == "mlp":
        hidden = [p["mlp_w1"]] + ([p["mlp_w2"]] if p["mlp_depth"] == 2 else [])
        return {"hidden": hidden, "mode": p["mlp_mode"], "kernel": "fast", "tanh": p["mlp_tanh"],
                "weight_bits": p["mlp_weight_bits"]}
    if fam == "poly" and p.get("poly_width") == 32:  # the wide path: its own knobs are fixed
        return {"degree": p["poly_degree"], "fit": "best", "coef_bits": 32, "split": False, "trim": 4,
                "rounding": True, "lsb": False, "width": 32}
    if fam == "poly":
        return {"degree": p["poly_degree"], "fit": "best", "coef_bits": p["poly_coef_bits"],
                "split": SPLITS[p["poly_split"]], "trim": 4, "rounding": p["poly_rounding"], "lsb": p["poly_lsb"]}
    if fam == "lut":
        k = [p["lut_kx"], p["lut_ky"]]
        return {"k": k, "bits": p["lut_bits"], "W": p["lut_W"], "fit": _fit(p["lut_fit"], "lut", k, problem),
                "symmetry": True}
    k = [p["hybrid_kx"], p["hybrid_ky"]]
    return {"k": k, "bits": 16, "W": p["hybrid_W"], "fit": _fit(p["hybrid_fit"], "hybrid", k, problem),
            "base": "affine", "coef_bits": p["hybrid_coef_bits"]}


def _fit(fit: str, fam: str, k: list[int], problem: Problem) -> str:
    """Minimax nodes only on exact samples of small tables, as the ladders (else it is slow and,
    on measured rows, fits the noise): a larger table falls back to least squares."""
    sp = spans(problem)[fam]
    small = problem.analytic and max((sp[a] >> k[a]) + 2 for a in range(2)) <= 14
    return fit if small else "lsq"


def params_of(fam: str, config: dict) -> dict | None:
    """The search parameters of a family's configuration (e.g. a ladder's), or None when the
    space cannot express it; the other families' knobs are left to the sampler."""
    if fam == "mlp":
        h = list(config["hidden"])
        if not 1 <= len(h) <= 2 or any(w not in MLP_WIDTHS for w in h) or config.get("tanh") not in MLP_TANH:
            return None
        return {"family": fam, "mlp_depth": len(h), "mlp_w1": h[0], **({"mlp_w2": h[1]} if len(h) == 2 else {}),
                "mlp_mode": config["mode"], "mlp_tanh": config["tanh"], "mlp_weight_bits": config["weight_bits"]}
    if fam == "poly" and config.get("width", 16) == 32:
        return {"family": fam, "poly_degree": config["degree"], "poly_width": 32}
    if fam == "poly":
        split = next((k for k, v in SPLITS.items() if v == config["split"]), None)
        if split is None or config.get("fit", "best") != "best" or config["coef_bits"] not in (16, 32):
            return None
        return {"family": fam, "poly_degree": config["degree"], "poly_coef_bits": config["coef_bits"],
                "poly_split": split, "poly_lsb": config["lsb"], "poly_rounding": config["rounding"], "poly_width": 16}
    k = [int(v) for v in config["k"]]
    out = {"family": fam, f"{fam}_kx": k[0], f"{fam}_ky": k[1], f"{fam}_W": config["W"], f"{fam}_fit": config["fit"]}
    out.update({"lut_bits": config["bits"]} if fam == "lut" else {"hybrid_coef_bits": config["coef_bits"]})
    return out
