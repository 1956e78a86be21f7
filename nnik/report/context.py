"""What every section reads: the inputs, the output folder, units, and a guarded plot call."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from nnik.report.document import Fig, Section
from nnik.report.inputs import Inputs, short_exc
from nnik.report.units import physical_units


class Context:
    """The state a section builds from: ``inp`` (Inputs), ``m`` (metrics.json), ``out`` (the
    folder the PNGs go to), ``outputs``, ``n_out``, ``unit``, ``phys`` / ``phys_reason``
    (physical units or why not), ``analytic`` (exact IK known) and ``derived_fixed``."""

    def __init__(self, inp: Inputs, out_dir: Path):
        self.inp = inp
        self.m = inp.metrics
        self.out = out_dir
        self.outputs = list(self.m["outputs"])
        self.n_out = len(self.outputs)
        self.unit = self.m["unit"]
        self.phys, self.phys_reason = physical_units(inp.scenario, self.n_out)
        self.analytic = bool(getattr(getattr(inp.scenario, "mechanism", None), "analytic", False))
        self.derived_fixed = self._derived_fixed()

    def plot(self, sec: Section, fn: Callable[[], Fig | str]) -> None:
        """Run a plot; a string result (or an exception) is a reason shown as "not run"."""
        try:
            r = fn()
        except OSError:  # a full disk or an unwritable folder is the command's error, not the picture's
            raise
        except Exception as exc:  # noqa: BLE001 - one broken picture must not sink the report
            r = f"picture failed ({short_exc(exc)})"
        if isinstance(r, Fig):
            sec.figures.append(r)
        else:
            sec.not_run.append(r)

    def _derived_fixed(self) -> dict | None:
        """RMS/p99 of the delivered commands and position errors, from fixed_eval.npz."""
        fe = self.inp.fixed_eval
        if fe is None:
            return None
        e = np.abs(fe["q_delivered"] - fe["q_true"])
        d = {"rms": np.sqrt((e**2).mean(0)).tolist(), "p99": np.percentile(e, 99, axis=0).tolist(),
             "max": e.max(0).tolist(), "position_um": None}
        scn = self.inp.scenario
        if scn is not None and self.analytic:
            try:
                from nnik.implementations.mlp.evaluate import position_error_um

                d["position_um"] = position_error_um(scn, fe["q_delivered"], fe["p_test"])
            except Exception:  # noqa: BLE001
                d["position_um"] = None
        return d
