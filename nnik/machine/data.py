"""Datasets: sample the workspace, label with the exact IK in actuator units, split, scale, save."""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from nnik.errors import NnikError
from nnik.machine.kinematics.base import Workspace
from nnik.machine.kinematics.measured import split_sizes
from nnik.machine.scenario import Scenario

SPLITS = ("train", "val", "test")


def sample_points(ws: Workspace, n: int, method: str, seed: int) -> np.ndarray:
    """n points (mm) in the workspace rectangle, deterministic by seed."""
    if method == "sobol":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # n need not be a power of two
            u = qmc.Sobol(d=2, scramble=True, seed=seed).random(n)
    elif method == "uniform":
        u = np.random.default_rng(seed).random((n, 2))
    elif method == "grid":
        k = int(np.ceil(np.sqrt(n)))
        g = np.linspace(0.0, 1.0, k)
        u = np.stack(np.meshgrid(g, g, indexing="xy"), -1).reshape(-1, 2)
    else:
        raise ValueError(method)
    return ws.lo + u * (ws.hi - ws.lo)


def exact_targets(scn: Scenario, p: np.ndarray) -> np.ndarray:
    """Exact IK in actuator units (microsteps or LSB, float64) for positions p (mm)."""
    m = scn.mechanism
    return scn.actuator.to_units(m.inverse(p) - m.q_rest)


@dataclass
class Dataset:
    """Positions p (mm) and targets q (actuator units) per split."""

    p: dict[str, np.ndarray]
    q: dict[str, np.ndarray]
    meta: dict = field(default_factory=dict)

    def save(self, path: Path) -> None:
        arrays = {f"p_{s}": self.p[s] for s in SPLITS} | {f"q_{s}": self.q[s] for s in SPLITS}
        np.savez_compressed(path, meta=np.array(json.dumps(self.meta)), **arrays)

    @classmethod
    def load(cls, path: Path) -> "Dataset":
        src = str(path)
        if not Path(path).is_file():
            raise NnikError("dataset not found (run `nnik generate` first)", src)
        try:
            with np.load(path, allow_pickle=False) as z:
                p = {s: np.asarray(z[f"p_{s}"]) for s in SPLITS}
                q = {s: np.asarray(z[f"q_{s}"]) for s in SPLITS}
                meta = json.loads(str(z["meta"]))
        except Exception as exc:  # truncated, random or foreign file: zipfile, KeyError, ValueError, EOFError
            raise NnikError(f"not a readable nnik dataset ({type(exc).__name__}); run `nnik generate` again",
                            src) from None
        if not isinstance(meta, dict):
            raise NnikError("not an nnik dataset (its metadata is not a JSON object)", src)
        for s in SPLITS:
            for k, a in (("p", p[s]), ("q", q[s])):
                if a.ndim != 2 or a.shape[1] != 2 or len(a) == 0 or a.dtype.kind != "f":
                    raise NnikError(f"{k}_{s} has shape {a.shape} and dtype {a.dtype}; expected (N, 2) floats", src)
                if not np.all(np.isfinite(a)):
                    raise NnikError(f"{k}_{s} holds NaN or infinite values in {int((~np.isfinite(a)).any(1).sum())} rows",
                                    src)
            if len(p[s]) != len(q[s]):
                raise NnikError(f"p_{s} has {len(p[s])} rows but q_{s} has {len(q[s])}", src)
        return cls(p=p, q=q, meta=meta)


def build_dataset(scn: Scenario) -> Dataset:
    cfg = scn.dataset
    seed = cfg["seed"]
    if not scn.mechanism.analytic:
        return _split_measured(scn, seed)
    ws = scn.workspace
    p = {
        "train": sample_points(ws, cfg["n_train"], cfg["sampling"], seed),
        "val": sample_points(ws, cfg["n_val"], "uniform", seed + 1),
        # test: independent uniform points plus the rectangle's edges and corners, where
        # extrapolation errors peak
        "test": np.concatenate([sample_points(ws, cfg["n_test"], "uniform", seed + 2), ws.boundary(64)]),
    }
    q = {s: exact_targets(scn, p[s]) for s in SPLITS}
    for s in SPLITS:
        if not np.all(np.isfinite(q[s])):
            raise NnikError(f"the exact IK is not finite on the {s} set (singularity in the workspace?)", scn.source, "[workspace]")
    meta = {"scenario": scn.name, "scenario_hash": scn.fingerprint, "source": scn.source, "unit": scn.unit, "outputs": scn.outputs,
            "sampling": cfg["sampling"], "seed": seed, "truth": "analytic IK"}
    return Dataset(p, q, meta)


def _split_measured(scn: Scenario, seed: int) -> Dataset:
    m = scn.mechanism
    n = len(m.positions_mm)
    order = np.random.default_rng(seed).permutation(n)
    sizes = split_sizes(n)
    n_test, n_val = sizes["test"], sizes["val"]
    idx = {"test": order[:n_test], "val": order[n_test:n_test + n_val], "train": order[n_test + n_val:]}
    p = {s: m.positions_mm[i] for s, i in idx.items()}
    q = {s: m.commands[i] for s, i in idx.items()}
    meta = {"scenario": scn.name, "scenario_hash": scn.fingerprint, "source": scn.source, "unit": scn.unit, "outputs": scn.outputs,
            "sampling": "measured rows", "seed": seed, "truth": f"held-out rows of {m.csv_path.name}",
            "duplicates_merged": int(m.duplicates_merged), "copies": int(m.copies)}
    return Dataset(p, q, meta)


@dataclass
class Scaling:
    """x_n = (p_mm - in_center) / in_half;  q = affine(x_n) + out_mean + out_std * net(x_n).

    `affine` is the exact least-squares base in residual mode (zero in full mode). The numbers
    are stored so that export can fold them into integer multiplies and shifts.
    """

    in_center: np.ndarray
    in_half: np.ndarray
    out_mean: np.ndarray
    out_std: np.ndarray
    base_coef: np.ndarray  # (n_out, n_in), units per normalised input
    base_intercept: np.ndarray  # (n_out,)

    def normalize(self, p_mm: np.ndarray) -> np.ndarray:
        return (p_mm - self.in_center) / self.in_half

    def base(self, xn: np.ndarray) -> np.ndarray:
        return xn @ self.base_coef.T + self.base_intercept

    def to_dict(self) -> dict:
        return {k: np.asarray(v, dtype=np.float64).tolist() for k, v in self.__dict__.items()}

    @classmethod
    def from_dict(cls, d: dict) -> "Scaling":
        return cls(**{k: np.asarray(v, dtype=np.float64) for k, v in d.items()})
