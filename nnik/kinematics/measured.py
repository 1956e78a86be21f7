"""A machine known only by measurements: a CSV of measured head positions and motor commands.

Columns: x_um, y_um (the measured position) and q1, q2 (the motor positions, in actuator units,
that produced it). There is no analytic model; the test split is held-out rows.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.kinematics.base import Mechanism
from nnik.params import Param

COLUMNS = ("x_um", "y_um", "q1", "q2")
MIN_ROWS = 20


def read_measurements(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Read the calibration CSV -> (positions in mm (N, 2), motor commands in actuator units (N, 2))."""
    src = str(path)
    if not path.is_file():
        raise NnikError("file not found", src)
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    rows = [r for r in rows if r and not (len(r) == 1 and not r[0].strip())]
    if not rows:
        raise NnikError("empty CSV (expected a header x_um,y_um,q1,q2 and data rows)", src)
    header = tuple(c.strip() for c in rows[0])
    if header != COLUMNS:
        raise NnikError(f"header must be {','.join(COLUMNS)}, got {','.join(header)}", src, "line 1")
    data = []
    for lineno, row in enumerate(rows[1:], start=2):
        if len(row) != len(COLUMNS):
            raise NnikError(f"expected {len(COLUMNS)} values, got {len(row)}", src, f"line {lineno}")
        try:
            vals = [float(v) for v in row]
        except ValueError:
            raise NnikError(f"not a number in {row!r}", src, f"line {lineno}") from None
        if not np.all(np.isfinite(vals)):
            raise NnikError(f"NaN or infinite value in {row!r}", src, f"line {lineno}")
        data.append(vals)
    if len(data) < MIN_ROWS:
        raise NnikError(f"only {len(data)} data rows; need at least {MIN_ROWS}", src)
    a = np.array(data)
    return a[:, :2] / 1000.0, a[:, 2:]


class Measured(Mechanism):
    kind = "measured"
    family = "measured"
    analytic = False
    PARAMS = {"csv": Param("str", required=True, doc="calibration CSV, relative to the TOML")}

    def __init__(self, params, workspace, source="<scenario>"):
        super().__init__(params, workspace, source)
        self.csv_path = Path(params["csv"])
        self.positions_mm, self.commands = read_measurements(self.csv_path)
        lo, hi = workspace.lo, workspace.hi
        outside = np.any((self.positions_mm < lo - 1e-9) | (self.positions_mm > hi + 1e-9), axis=1)
        if outside.any():
            i = int(np.argmax(outside))
            raise NnikError(
                f"row {i + 1} at ({self.positions_mm[i, 0]:.3f}, {self.positions_mm[i, 1]:.3f}) mm lies "
                "outside [workspace]",
                str(self.csv_path),
            )

    def forward(self, q):
        raise NnikError("a measured mechanism has no analytic forward model", self.source, "[mechanism] kind")

    def inverse(self, p):
        raise NnikError("a measured mechanism has no analytic inverse model", self.source, "[mechanism] kind")
