"""Synthetic calibration data: 'measure' a simulated machine, as a user would with a probe.

For points spread over the workspace, the machine is commanded to whole microsteps (the exact
IK rounded), the true head position is the exact forward kinematics of those commands, and the
measurement adds Gaussian noise. The CSV has the columns `nnik.kinematics.measured` reads.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from nnik.data import exact_targets, sample_points
from nnik.errors import NnikError
from nnik.kinematics.base import Workspace
from nnik.scenario import Scenario

EDGE_MARGIN_MM = 0.05  # keep noisy measurements inside the workspace


def synthesize_measurements(scn: Scenario, path: Path, n: int, noise_um: float, seed: int) -> int:
    m = scn.mechanism
    if not m.analytic:
        raise NnikError("synth-csv needs an analytic machine to measure", scn.source, "[mechanism] kind")
    if n < 20 or not noise_um >= 0:
        raise NnikError(f"need n >= 20 and noise >= 0 (got n={n}, noise={noise_um})")
    ws = scn.workspace
    inner = Workspace((ws.x_mm[0] + EDGE_MARGIN_MM, ws.x_mm[1] - EDGE_MARGIN_MM),
                      (ws.y_mm[0] + EDGE_MARGIN_MM, ws.y_mm[1] - EDGE_MARGIN_MM))
    p_target = sample_points(inner, n, "sobol", seed)
    commands = np.rint(exact_targets(scn, p_target))
    p_true = m.forward(m.q_rest + scn.actuator.from_units(commands))
    rng = np.random.default_rng(seed + 7)
    p_meas_um = p_true * 1000 + rng.normal(0.0, noise_um, p_true.shape)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["x_um", "y_um", "q1", "q2"])
        for (x, y), (a, b) in zip(p_meas_um, commands):
            w.writerow([f"{x:.1f}", f"{y:.1f}", int(a), int(b)])
    return n
