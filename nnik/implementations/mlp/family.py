"""The ``mlp`` family: a small tanh MLP (full, or residual over an exact affine base) trained in
torch, quantised with range-analysed Q formats (:mod:`nnik.implementations.mlp.fixedpoint`) and emitted with the fast
hardware-multiply kernel or the portable C kernel (:mod:`nnik.export`). Every feature of the MLP
pipeline is kept; this module puts it behind the common interface.

Knobs: ``hidden`` (layer widths), ``mode`` (full | residual), ``kernel`` (fast | portable),
``tanh`` (variant, "default" = the kernel's own), ``weight_bits`` (16 | 8).
With ``input_unit_um = u`` other than 1, the trained model is re-expressed in a coordinate
system whose "micrometre" is u um (workspace and input scaling divided by u): the integer model
and its C then take inputs in units of u um, and the network is unchanged.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.problem import Problem


def _model_key(config: dict) -> tuple:
    return ("mlp_model", tuple(config["hidden"]), config["mode"])


def own_config(scn) -> dict:
    """The scenario's own network ([network], [export]): the family's ladder, and what `nnik run`
    keeps as model.pt."""
    return {"hidden": list(scn.network["hidden"]), "mode": scn.network["mode"], "kernel": scn.export["kernel"],
            "tanh": scn.export["tanh"], "weight_bits": scn.export["weight_bits"]}


def remember_trained(problem: Problem, model) -> dict:
    """Put an already trained model (model.pt of a finished `nnik run`, or the one a measured
    machine's reference was fitted with) into the problem's cache; returns the matching config."""
    cfg = own_config(model.scenario)
    problem.cache[_model_key(cfg)] = model
    return cfg


def trained(problem: Problem):
    """The network the family's fit trained (or was given) for the scenario's own configuration."""
    return problem.cache.get(_model_key(own_config(problem.scn)))


def train_network(scn, dataset, config: dict, progress: bool = False):
    """The family's training: the network of ``config`` on the scenario's samples, with the
    scenario's [training] budget (seeded: the same data give the same weights)."""
    from nnik.implementations.mlp.train import train_model

    net = {**scn.network, "hidden": tuple(config["hidden"]), "mode": config["mode"]}
    return train_model(dataclasses.replace(scn, network=net), dataset, progress=progress)


def _in_units(problem: Problem, model):
    """The model in coordinates where one "micrometre" is one input unit, and its refit set."""
    from nnik.machine.data import Scaling
    from nnik.machine.kinematics.base import Workspace

    k = 1.0 / problem.unit_um
    scn = problem.scn
    ws = Workspace(tuple(np.asarray(scn.workspace.x_mm) * k), tuple(np.asarray(scn.workspace.y_mm) * k))
    s = model.scaling
    scaling = Scaling(s.in_center * k, s.in_half * k, s.out_mean, s.out_std, s.base_coef, s.base_intercept)
    moved = dataclasses.replace(model, scaling=scaling, scenario=dataclasses.replace(scn, workspace=ws))
    if problem.analytic:
        pts, q = problem.fit_samples(121)
        pts = np.rint(pts)
        q = problem.truth(pts)
    else:
        pts, q = problem.fit_samples()
    return moved, (pts / 1000.0, q)


# a search trial's MLP trains on a small budget so that it takes seconds (the scenario's own network keeps
# the budget `nnik run` trained it with)
FAST_TRAINING = {"adam_steps": 400, "lbfgs_rounds": 40, "restarts": 1, "patience": 15}


def fast_problem(problem: Problem) -> Problem:
    """The problem, changed in place to a small MLP training budget (its check set and its cache,
    with the scenario's trained model, kept)."""
    scn = problem.scn
    problem.scn = dataclasses.replace(scn, training={**scn.training, **FAST_TRAINING})
    return problem


class MlpImpl(Implementation):
    family = "mlp"
    doc = "tanh MLP, fixed point, fast hardware-multiply kernel or portable C"
    portable_checked_on = ("avr",)
    portable_not_checked_reason = ("SDCC takes minutes to compile the fast kernel's unrolled portable path; the "
                                   "portable kernel itself is verified on PIC18 by `nnik verify --target pic18`")
    front_checked_on = ("avr",)
    front_not_checked_reason = ("SDCC takes minutes to compile each MLP for pic18: of the MLP's front points only its "
                                "best is compiled there (this one shows its estimate)")

    def __init__(self, problem: Problem, config: dict, model, im):
        super().__init__(problem, config)
        self.model = model  # nnik.implementations.mlp.train.TrainedModel
        self.im = im  # nnik.implementations.mlp.fixedpoint.IntegerModel

    @classmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        """The scenario's own network (trained here, by :meth:`fit`); the search explores more."""
        return [own_config(problem.scn)]

    @classmethod
    def fit(cls, problem: Problem, config: dict) -> "MlpImpl":
        from nnik.implementations.mlp import quantize as fx

        key = _model_key(config)
        model = problem.cache.get(key)
        if model is None:  # the family's training: `nnik run`'s ladder trains the scenario's network here
            model = train_network(problem.scn, problem.dataset, config)
            problem.cache[key] = model
        ds = problem.dataset
        tanh = None if config.get("tanh", "default") == "default" else config["tanh"]
        if problem.unit_um == 1.0:
            q_model, calib = model, fx.calibration_set(model, ds.p["train"], ds.q["train"])
        else:
            q_model, calib = _in_units(problem, model)
        im = fx.quantize(q_model, tanh_variant=tanh, weight_bits=config.get("weight_bits", 16), calib=calib,
                         kernel=config.get("kernel", "fast"))
        return cls(problem, config, model, im)

    def run(self, in_units: np.ndarray) -> IntRun:
        total, out, flags = self.im.run(np.asarray(in_units, dtype=np.int64))
        return IntRun(pre=total / float(2**self.im.out.F), out=out, flags=flags)

    def render_c(self) -> dict[str, str]:
        from nnik.implementations.mlp.export import render_model_c

        return render_model_c(self.im, self.problem.scn.source)

    def render_source(self) -> str:
        return self.render_c()[f"{self.problem.name}.c"]

    def estimate(self, target: str) -> dict:
        from nnik.implementations.mlp.cost import estimate

        e = estimate(self.im, target)
        return {"cycles": float(e["cycles"]), "flash_bytes": int(e["flash_bytes"]), "ram_bytes": int(e["ram_bytes"]),
                "validated": bool(e.get("validated", True))}

    def model_bytes(self) -> int:
        return int(self.im.weights_bytes() + self.im.tanh_bytes())

    def describe(self) -> str:
        shape = "-".join(map(str, self.im.shape))
        return f"mlp {shape} {self.config['mode']}, {self.im.kernel} kernel, tanh {self.im.tanh_variant}, int{self.im.weight_bits}"


IMPLEMENTATION = MlpImpl
