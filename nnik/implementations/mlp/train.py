"""Training: a small float64 tanh MLP, full or as a residual over an exact affine base.

Adam warm-up, then L-BFGS (strong Wolfe) refinement with early stopping on the validation set,
with a few deterministic restarts; the best validation state wins. The budget is counted in
iterations (adam_steps, lbfgs_rounds, patience, restarts), so the same scenario and seed give the
same model on any machine. [training] max_seconds is an optional cap that only the user sets: when
it cuts training short, `stopped_by` says "wall_clock" (metrics.json and the report record it, the
CLI warns) and the result is not reproducible.
"""

from __future__ import annotations

import copy
import io
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from sklearn.linear_model import LinearRegression
from torch import nn
from nnik.progress import bar as progress_bar

from nnik.machine.data import Dataset, Scaling
from nnik.errors import NnikError
from nnik.files.atomic_write import write_file_atomic
from nnik.machine.scenario import Scenario

MODEL_FORMAT = 1
TIME_FILE = "train_time.json"  # beside model.pt: how long training took (a figure, never an input)
SMALL_PROBLEM = 4_000_000  # training rows x hidden neurons below which one thread is faster
MAX_FIT_ROWS = 20_000  # rows per split that full-batch training fits on (a fixed subset beyond)


class MLP(nn.Module):
    """inputs -> tanh hidden layers -> linear outputs, float64."""

    def __init__(self, n_in: int, hidden: tuple[int, ...], n_out: int):
        super().__init__()
        layers: list[nn.Module] = []
        width = n_in
        for h in hidden:
            layers += [nn.Linear(width, h, dtype=torch.float64), nn.Tanh()]
            width = h
        layers.append(nn.Linear(width, n_out, dtype=torch.float64))
        self.net = nn.Sequential(*layers)
        self.shape = (n_in, *hidden, n_out)

    def forward(self, x):
        return self.net(x)

    def dense_layers(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """[(W (out, in), b (out,)), ...] as float64 numpy, first layer first."""
        return [
            (m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
            for m in self.net
            if isinstance(m, nn.Linear)
        ]


@dataclass
class TrainedModel:
    net: MLP
    scaling: Scaling
    scenario: Scenario
    history: list[dict] = field(default_factory=list)
    train_seconds: float = 0.0
    normalize: bool = True
    stopped_by: str = "budget"  # "budget" (iterations, patience) or "wall_clock" (the safety net fired)

    def predict(self, p_mm: np.ndarray) -> np.ndarray:
        """Positions (mm) -> actuator units, float64."""
        s = self.scaling
        xn = s.normalize(p_mm)
        with torch.no_grad():
            y = self.net(torch.from_numpy(xn)).numpy()
        return s.base(xn) + s.out_mean + s.out_std * y

    def save(self, path: Path) -> None:
        """model.pt (atomically) and, beside it, the training's wall-clock time (TIME_FILE). model.pt
        holds nothing that depends on the machine's load, so its bytes (and the hashes that the pick
        records) are the same on an idle or a loaded machine. Written whole or not at all: torch's
        own file writer turns a full disk into a RuntimeError, so the bytes are made in memory."""
        buf = io.BytesIO()
        torch.save(
            {
                "format": MODEL_FORMAT,
                "shape": list(self.net.shape),
                "state_dict": self.net.state_dict(),
                "scaling": self.scaling.to_dict(),
                "scenario_raw": self.scenario.raw,
                "scenario_source": self.scenario.source,
                "scenario_base_dir": str(self.scenario.base_dir),
                "history": self.history,  # counted in optimiser steps: no wall-clock time in this file
                "normalize": self.normalize,
                "stopped_by": self.stopped_by,
            },
            buf,
        )
        write_file_atomic(Path(path), buf.getvalue())
        write_file_atomic(Path(path).parent / TIME_FILE, json.dumps({"train_seconds": self.train_seconds}) + "\n")

    @classmethod
    def load(cls, path: Path) -> "TrainedModel":
        from nnik.machine.scenario import Scenario

        path = Path(path)
        if not path.is_file():
            raise NnikError("model not found (run `nnik train` first)", str(path))
        try:
            blob = torch.load(path, weights_only=True)
        except Exception as exc:  # a corrupt or foreign file
            raise NnikError(f"not an nnik model file ({type(exc).__name__})", str(path)) from None
        if not isinstance(blob, dict) or blob.get("format") != MODEL_FORMAT:
            raise NnikError("not an nnik model file (unknown format)", str(path))
        try:
            shape = [int(v) for v in blob["shape"]]
            if len(shape) < 3 or min(shape) < 1 or max(shape) > 4096:
                raise ValueError(f"shape {shape}")
            net = MLP(shape[0], tuple(shape[1:-1]), shape[-1])
            net.load_state_dict(blob["state_dict"])
            scaling = Scaling.from_dict(blob["scaling"])
            raw, source, base = blob["scenario_raw"], str(blob["scenario_source"]), Path(blob["scenario_base_dir"])
            history, normalize = list(blob["history"]), bool(blob["normalize"])
            stopped_by = str(blob.get("stopped_by", "budget"))
        except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as exc:
            reason = " ".join(line.strip() for line in str(exc).splitlines())[:160]
            raise NnikError(f"corrupt nnik model file ({type(exc).__name__}: {reason}); run `nnik train` again",
                            str(path)) from None
        scn = Scenario.from_dict(raw, source, base)
        return cls(net, scaling, scn, history, read_train_seconds(path), normalize, stopped_by)


def read_train_seconds(model_path: Path) -> float:
    """The training time recorded beside model.pt (NaN, shown as "—", when it is missing or unreadable)."""
    try:
        v = json.loads((Path(model_path).parent / TIME_FILE).read_text())["train_seconds"]
        return float(v) if isinstance(v, (int, float)) and math.isfinite(v) and v >= 0 else math.nan
    except (OSError, ValueError, KeyError, TypeError):
        return math.nan


def make_scaling(scn: Scenario, ds: Dataset, normalize: bool) -> Scaling:
    ws = scn.workspace
    center, half = (ws.center, ws.half) if normalize else (np.zeros(2), np.ones(2))
    xn = (ds.p["train"] - center) / half
    q = ds.q["train"]
    n_out = q.shape[1]
    coef, intercept = np.zeros((n_out, 2)), np.zeros(n_out)
    if scn.network["mode"] == "residual":
        lr = LinearRegression().fit(xn, q)
        coef, intercept = lr.coef_.astype(np.float64), lr.intercept_.astype(np.float64)
    r = q - (xn @ coef.T + intercept)
    std = r.std(0)
    std = np.where(std > 1e-12, std, 1.0)
    return Scaling(center, half, r.mean(0), std, coef, intercept)


def _rows(n: int, seed: int) -> np.ndarray:
    """Which rows full-batch training uses: all of them up to MAX_FIT_ROWS, else a fixed random
    subset (10^6 measured rows would make every Adam and L-BFGS step a million-row pass, while a
    network of a few dozen weights is fully determined long before that)."""
    if n <= MAX_FIT_ROWS:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, MAX_FIT_ROWS, replace=False))


def _tensors(scaling: Scaling, p: np.ndarray, q: np.ndarray):
    xn = scaling.normalize(p)
    y = (q - scaling.base(xn) - scaling.out_mean) / scaling.out_std
    return torch.from_numpy(xn), torch.from_numpy(y)


def train_model(scn: Scenario, ds: Dataset, normalize: bool | None = None, progress: bool = True) -> TrainedModel:
    cfg = scn.training
    normalize = scn.network["normalize"] if normalize is None else normalize
    scaling = make_scaling(scn, ds, normalize)
    tr, va = _rows(len(ds.p["train"]), scn.dataset["seed"]), _rows(len(ds.p["val"]), scn.dataset["seed"] + 1)
    xt, yt = _tensors(scaling, ds.p["train"][tr], ds.q["train"][tr])
    xv, yv = _tensors(scaling, ds.p["val"][va], ds.q["val"][va])
    # Small problems run on one thread: their ops are too small to split, and with a second thread
    # OpenMP's waiting made training 25x slower on a loaded 2-core machine (33 s vs 1.3 s). The
    # count depends only on the problem, so the same budget gives the same model everywhere.
    torch.set_num_threads(1 if len(xt) * sum(scn.network["hidden"]) < SMALL_PROBLEM else 2)
    t_start = time.perf_counter()
    cap = cfg.get("max_seconds")
    deadline = t_start + cap if cap else float("inf")  # the user's optional cap, not the budget
    best: tuple[float, dict, int] | None = None
    history: list[dict] = []
    stopped_by = "budget"
    bar = progress_bar(total=cfg["restarts"], desc=f"train {scn.name}", unit="restart", disable=not progress, leave=False, mininterval=1.0)
    for restart in range(cfg["restarts"]):
        torch.manual_seed(1000 * scn.dataset["seed"] + restart)
        net = MLP(2, scn.network["hidden"], yt.shape[1])
        val, state, cut = _fit_one(net, xt, yt, xv, yv, cfg, deadline, restart, history, t_start, bar)
        if best is None or val < best[0]:
            best = (val, state, restart)
        bar.update(1)
        if cut:
            stopped_by = "wall_clock"
            break
    bar.close()
    net = MLP(2, scn.network["hidden"], yt.shape[1])
    net.load_state_dict(best[1])
    for h in history:
        h["best"] = h["restart"] == best[2]
    return TrainedModel(net, scaling, scn, history, time.perf_counter() - t_start, normalize, stopped_by)


def _fit_one(net, xt, yt, xv, yv, cfg, deadline, restart, history, t_start, bar):
    """One initialisation: Adam then L-BFGS. Returns (best val loss, its state, cut by the deadline)."""
    mse = nn.MSELoss()

    def val_loss():
        with torch.no_grad():
            return float(mse(net(xv), yv))

    def log(phase, step, train_loss):
        history.append({"restart": restart, "phase": phase, "step": step, "train": float(train_loss), "val": val_loss()})

    opt = torch.optim.Adam(net.parameters(), lr=cfg["adam_lr"])
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, max(1, cfg["adam_steps"]), eta_min=cfg["adam_lr"] / 100)
    for step in range(cfg["adam_steps"]):
        opt.zero_grad()
        loss = mse(net(xt), yt)
        loss.backward()
        opt.step()
        sched.step()
        if step % 100 == 0:
            log("adam", step, loss.item())
        if time.perf_counter() > deadline:
            return val_loss(), copy.deepcopy(net.state_dict()), True

    lbfgs = torch.optim.LBFGS(net.parameters(), lr=1.0, max_iter=25, history_size=50,
                              line_search_fn="strong_wolfe", tolerance_grad=1e-14, tolerance_change=1e-16)

    def closure():
        lbfgs.zero_grad()
        loss = mse(net(xt), yt)
        loss.backward()
        return loss

    best_val, best_state, stale = val_loss(), copy.deepcopy(net.state_dict()), 0
    for rnd in range(cfg["lbfgs_rounds"]):
        loss = lbfgs.step(closure)
        log("lbfgs", cfg["adam_steps"] + rnd, loss.item())
        v = history[-1]["val"]
        if not np.isfinite(v):
            break
        stale = 0 if v < best_val * (1 - 1e-3) else stale + 1
        if v < best_val:
            best_val, best_state = v, copy.deepcopy(net.state_dict())
        bar.set_postfix(restart=restart, val=f"{best_val:.3e}", refresh=False)  # drawn at mininterval
        if stale >= cfg["patience"]:
            break
        if time.perf_counter() > deadline:
            return best_val, best_state, True
    return best_val, best_state, False
