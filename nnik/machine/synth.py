"""Synthetic calibration data: 'measure' a simulated machine, as a user would with a probe.

Two ways of measuring (``readings``):

* ``commanded`` (default): for points spread over the workspace, the machine is commanded to
  whole microsteps (the exact IK rounded), the true head position is the exact forward
  kinematics of those commands, and the measurement adds Gaussian noise to the position;
* ``rounded``: marks at known positions (plus the optional position noise); the head is jogged
  onto each mark and the step counter is read, so q1/q2 are the exact IK rounded to whole
  actuator units: +-0.5 of rounding (variance 1/12) on every reading.

Marks are Sobol-scattered or a k x k grid (``sampling``), ``inset_mm`` inside the workspace.
The CSV has the columns `nnik.machine.kinematics.measured` reads.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from nnik.machine.data import exact_targets, sample_points
from nnik.errors import NnikError
from nnik.machine.kinematics.base import Workspace
from nnik.machine.scenario import MAX_SEED, Scenario

EDGE_MARGIN_MM = 0.05  # keep noisy measurements inside the workspace
N_MIN, N_MAX = 20, 1_000_000  # marks: enough for a fit, few enough for memory
NOISE_UM_MAX = 1e4  # 1 sigma: 10 mm of noise is no measurement
READINGS = ("commanded", "rounded")
SAMPLING = ("sobol", "grid")


def synthesize_measurements(scn: Scenario, path: Path, n: int, noise_um: float, seed: int,
                            readings: str = "commanded", sampling: str = "sobol",
                            inset_mm: float = EDGE_MARGIN_MM) -> int:
    """Write the CSV; returns its number of rows (a grid has ceil(sqrt(n))^2 of them)."""
    text, rows = measurements_csv(scn, n, noise_um, seed, readings, sampling, inset_mm)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, newline="")
    return rows


def measurements_csv(scn: Scenario, n: int, noise_um: float, seed: int, readings: str = "commanded",
                     sampling: str = "sobol", inset_mm: float = EDGE_MARGIN_MM) -> tuple[str, int]:
    """The CSV's text and its number of rows (every argument checked first, nothing written)."""
    m = scn.mechanism
    if not m.analytic:
        raise NnikError("synth-csv needs an analytic machine to measure", scn.source, "[mechanism] kind")
    if not (N_MIN <= n <= N_MAX) or not 0 <= noise_um <= NOISE_UM_MAX:
        raise NnikError(f"need {N_MIN} <= n <= {N_MAX} and 0 <= noise <= {NOISE_UM_MAX:g} um (got n={n}, noise={noise_um})")
    if not 0 <= seed <= MAX_SEED:
        raise NnikError(f"must be in [0, {MAX_SEED}], got {seed}", None, "--seed")
    if readings not in READINGS or sampling not in SAMPLING:
        raise NnikError(f"readings must be one of {', '.join(READINGS)} and sampling one of {', '.join(SAMPLING)}")
    ws = scn.workspace
    half = min(np.ptp(ws.x_mm), np.ptp(ws.y_mm)) / 2
    if not EDGE_MARGIN_MM <= inset_mm < half:
        raise NnikError(f"inset must be in [{EDGE_MARGIN_MM}, {half:g}) mm, got {inset_mm}")
    inner = Workspace((ws.x_mm[0] + inset_mm, ws.x_mm[1] - inset_mm), (ws.y_mm[0] + inset_mm, ws.y_mm[1] - inset_mm))
    p_target = sample_points(inner, n, sampling, seed)
    commands = np.rint(exact_targets(scn, p_target))
    # rounded: the head sits on the mark, the counter rounds; commanded: the head sits where the
    # whole-step command put it
    p_true = p_target if readings == "rounded" else m.forward(m.q_rest + scn.actuator.from_units(commands))
    rng = np.random.default_rng(seed + 7)
    p_meas_um = p_true * 1000 + rng.normal(0.0, noise_um, p_true.shape)
    fh = io.StringIO(newline="")
    w = csv.writer(fh)
    w.writerow(["x_um", "y_um", "q1", "q2"])
    for (x, y), (a, b) in zip(p_meas_um, commands):
        w.writerow([f"{x:.1f}", f"{y:.1f}", int(a), int(b)])
    return fh.getvalue(), len(commands)
