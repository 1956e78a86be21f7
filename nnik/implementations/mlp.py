"""The ``mlp`` family: a small tanh MLP (full, or residual over an exact affine base) trained in
torch, quantised with range-analysed Q formats (:mod:`nnik.fixedpoint`) and emitted with the fast
hardware-multiply kernel or the portable C kernel (:mod:`nnik.export`). Every feature of the MLP
pipeline is kept; this module puts it behind the common interface.

Knobs: ``hidden`` (layer widths), ``mode`` (full | residual), ``kernel`` (fast | portable),
``tanh`` (variant, "default" = the kernel's own), ``weight_bits`` (16 | 8).
The MLP's inputs are integer micrometres, so the family needs ``input_unit_um = 1``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.problem import Problem


def _model_key(config: dict) -> tuple:
    return ("mlp_model", tuple(config["hidden"]), config["mode"])


def remember_trained(problem: Problem, model) -> dict:
    """Put an already trained model (e.g. ``nnik run``'s) into the problem's cache; returns the
    matching config."""
    scn = model.scenario
    cfg = {"hidden": list(scn.network["hidden"]), "mode": scn.network["mode"], "kernel": scn.export["kernel"],
           "tanh": scn.export["tanh"], "weight_bits": scn.export["weight_bits"]}
    problem.cache[_model_key(cfg)] = model
    return cfg


class MlpImpl(Implementation):
    family = "mlp"
    doc = "tanh MLP, fixed point, fast hardware-multiply kernel or portable C"

    def __init__(self, problem: Problem, config: dict, model, im):
        super().__init__(problem, config)
        self.model = model  # nnik.train.TrainedModel
        self.im = im  # nnik.fixedpoint.IntegerModel

    @classmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        """The scenario's own network (trained by the pipeline); the search explores more."""
        scn = problem.scn
        return [{"hidden": list(scn.network["hidden"]), "mode": scn.network["mode"], "kernel": scn.export["kernel"],
                 "tanh": scn.export["tanh"], "weight_bits": scn.export["weight_bits"]}]

    @classmethod
    def fit(cls, problem: Problem, config: dict) -> "MlpImpl":
        from nnik import fixedpoint as fx

        if problem.unit_um != 1.0:
            raise NnikError("the mlp family takes integer micrometre inputs (input_unit_um = 1)")
        key = _model_key(config)
        model = problem.cache.get(key)
        if model is None:
            from nnik.train import train_model

            scn = problem.scn
            net = {**scn.network, "hidden": tuple(config["hidden"]), "mode": config["mode"]}
            model = train_model(dataclasses.replace(scn, network=net), problem.dataset, progress=False)
            problem.cache[key] = model
        ds = problem.dataset
        tanh = None if config.get("tanh", "default") == "default" else config["tanh"]
        im = fx.quantize(model, tanh_variant=tanh, weight_bits=config.get("weight_bits", 16),
                         calib=fx.calibration_set(model, ds.p["train"], ds.q["train"]),
                         kernel=config.get("kernel", "fast"))
        return cls(problem, config, model, im)

    def run(self, in_units: np.ndarray) -> IntRun:
        total, out, flags = self.im.run(np.asarray(in_units, dtype=np.int64))
        return IntRun(pre=total / float(2**self.im.out.F), out=out, flags=flags)

    def render_c(self) -> dict[str, str]:
        from nnik.export import render_model_c

        return render_model_c(self.im, self.problem.scn.source)

    def render_source(self) -> str:
        return self.render_c()[f"{self.problem.name}.c"]

    def estimate(self, target: str) -> dict:
        from nnik.estimate import estimate

        e = estimate(self.im, target)
        return {"cycles": float(e["cycles"]), "flash_bytes": int(e["flash_bytes"]), "ram_bytes": int(e["ram_bytes"]),
                "validated": bool(e.get("validated", True))}

    def model_bytes(self) -> int:
        return int(self.im.weights_bytes() + self.im.tanh_bytes())

    def describe(self) -> str:
        shape = "-".join(map(str, self.im.shape))
        return f"mlp {shape} {self.config['mode']}, {self.im.kernel} kernel, tanh {self.im.tanh_variant}, int{self.im.weight_bits}"


IMPLEMENTATION = MlpImpl
