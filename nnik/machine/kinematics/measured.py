"""A machine known only by measurements: a CSV of measured head positions and motor commands.

Columns: x_um, y_um (the measured position) and q1, q2 (the motor positions, in actuator units,
that produced it). There is no analytic model; the test split is held-out rows.
"""

from __future__ import annotations

import csv
import io
import warnings
from pathlib import Path

import numpy as np

from nnik.errors import NnikError, NnikWarning
from nnik.machine.kinematics.base import Mechanism
from nnik.machine.params import Param

COLUMNS = ("x_um", "y_um", "q1", "q2")
MIN_ROWS = 20
COVERAGE_GRID = 4  # every cell of a 4 x 4 grid over [workspace] must hold measured rows
MAX_FIELD = 100  # characters in one CSV field; a number never needs more


def _read_text(path: Path) -> str:
    raw = path.read_bytes()
    try:
        return raw.decode("utf-8-sig")  # a UTF-8 byte-order mark (Excel writes one) is accepted
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise NnikError(f"not UTF-8 text: byte 0x{raw[exc.start]:02x} at offset {exc.start} "
                        "(save the CSV as UTF-8 or plain ASCII)", str(path), f"line {line}") from None


_READ_CACHE: dict = {}  # (path, size, mtime) -> arrays: every stage reloads the scenario, the CSV once


def read_measurements(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Read the calibration CSV -> (positions in mm (N, 2), motor commands in actuator units (N, 2))."""
    src = str(path)
    if path.is_dir():
        raise NnikError("a directory, not a CSV of measured marks", src)
    if not path.is_file():
        raise NnikError("file not found", src)
    st = path.stat()
    key = (str(path.resolve()), st.st_size, st.st_mtime_ns)
    if key not in _READ_CACHE:
        _READ_CACHE.clear()
        _READ_CACHE[key] = _parse_measurements(path)
    p_mm, q = _READ_CACHE[key]
    return p_mm.copy(), q.copy()


def _parse_measurements(path: Path) -> tuple[np.ndarray, np.ndarray]:
    src = str(path)
    text = _read_text(path)
    reader = csv.reader(io.StringIO(text, newline=""))
    check_fields = max(map(len, text.splitlines()), default=0) > MAX_FIELD
    lines, rows = [], []
    start = 1  # the line the row being read starts on (a quoted field may span lines)
    try:
        for row in reader:
            if row and not (len(row) == 1 and not row[0].strip()):
                if check_fields and any(len(v) > MAX_FIELD for v in row):
                    raise NnikError(f"a field of {max(map(len, row))} characters (a number needs at most {MAX_FIELD})",
                                    src, f"line {start}")
                lines.append(start)
                rows.append(row)
            start = reader.line_num + 1
    except csv.Error as exc:
        raise NnikError(f"malformed CSV ({exc})", src, f"line {start}") from None
    if not rows:
        raise NnikError("empty CSV (expected a header x_um,y_um,q1,q2 and data rows)", src)
    header = tuple(c.strip() for c in rows[0])
    if header != COLUMNS:
        shown = ",".join(header).encode("ascii", "backslashreplace").decode()
        raise NnikError(f"header must be {','.join(COLUMNS)}, got {shown}", src, "line 1")
    lines, rows = lines[1:], rows[1:]
    widths = np.fromiter(map(len, rows), dtype=np.int64, count=len(rows))
    if np.any(widths != len(COLUMNS)):
        k = int(np.argmax(widths != len(COLUMNS)))
        raise NnikError(f"expected {len(COLUMNS)} values, got {widths[k]}", src, f"line {lines[k]}")
    try:
        data = np.array(rows, dtype=np.float64).reshape(-1, len(COLUMNS))  # fast path, in C
    except ValueError:
        data = None
    if data is None:
        for lineno, row in zip(lines, rows):  # find the line that does not parse
            try:
                [float(v) for v in row]
            except ValueError:
                raise NnikError(f"not a number in {row!r}", src, f"line {lineno}") from None
        data = np.array([[float(v) for v in row] for row in rows], dtype=np.float64).reshape(-1, len(COLUMNS))
    bad = ~np.isfinite(data).all(axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        raise NnikError(f"NaN or infinite value in {rows[k]!r}", src, f"line {lines[k]}")
    if len(data) < MIN_ROWS:
        raise NnikError(f"only {len(data)} data rows; need at least {MIN_ROWS}", src)
    return data[:, :2] / 1000.0, data[:, 2:]


def merge_duplicates(p_mm: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """One row per distinct position (commands averaged), so that no position sits in both the
    training and the held-out rows. Returns (positions, commands, rows merged away)."""
    order = np.lexsort((p_mm[:, 1], p_mm[:, 0]))
    ps = p_mm[order]
    if not np.any(np.all(ps[1:] == ps[:-1], axis=1)):  # the usual case, without np.unique's cost
        return p_mm, q, 0
    uniq, first, inverse = np.unique(p_mm, axis=0, return_index=True, return_inverse=True)
    rank = np.empty(len(uniq), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(uniq))  # keep the file's order of first appearance
    group = rank[inverse.reshape(-1)]
    counts = np.bincount(group, minlength=len(uniq)).astype(np.float64)
    qm = np.stack([np.bincount(group, weights=q[:, j], minlength=len(uniq)) for j in range(q.shape[1])], 1)
    return p_mm[np.sort(first)], qm / counts[:, None], len(p_mm) - len(uniq)


def drop_copies(p_mm: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The rows without those that repeat an earlier row exactly, position and readings alike (a
    copied row, or a mark read again that measured nothing new: its spread would pass for a
    perfect instrument). Returns (positions, commands, copies dropped), in the file's order."""
    rows = np.concatenate([p_mm, q], axis=1)
    order = np.lexsort(rows.T[::-1])
    same = np.all(rows[order][1:] == rows[order][:-1], axis=1)
    if not same.any():  # the usual case, without np.unique's cost
        return p_mm, q, 0
    _, first = np.unique(rows, axis=0, return_index=True)
    keep = np.sort(first)
    return p_mm[keep], q[keep], len(rows) - len(keep)


SPLIT_FRACTIONS = {"test": 0.25, "val": 0.15}  # of the distinct marks held out; the rest trains
SPLIT_MIN = 5  # marks in each held-out split at least


def split_sizes(n: int) -> dict[str, int]:
    """How many of n distinct marks test, validate and train."""
    n_test, n_val = (max(SPLIT_MIN, int(round(n * SPLIT_FRACTIONS[s]))) for s in ("test", "val"))
    return {"test": n_test, "val": n_val, "train": n - n_test - n_val}


FOLLOW_R2 = 0.5  # a quadratic in the position must explain at least this fraction of each reading's variance
INDEPENDENT = 1e-3  # the affine map's smaller singular value at least this fraction of its larger one


def check_readings(p_mm: np.ndarray, q: np.ndarray, src: str) -> None:
    """Readings that cannot be a machine's inverse kinematics, refused: a column that never
    changes, a column the position does not explain (a quadratic in x, y explains less than
    FOLLOW_R2 of its variance: shuffled or unrelated columns), or two columns that move as one
    (the head then reaches a line, not the rows' area)."""
    for o, name in enumerate(COLUMNS[2:]):
        if np.ptp(q[:, o]) == 0:
            raise NnikError(f"{name} is {q[0, o]:g} on every row: the readings do not change with the position", src)
    span = np.maximum(np.ptp(p_mm, axis=0), 1e-12)
    x = (p_mm - p_mm.min(0)) / span * 2 - 1
    feats = np.stack([np.ones(len(x)), x[:, 0], x[:, 1], x[:, 0] ** 2, x[:, 0] * x[:, 1], x[:, 1] ** 2], 1)
    coef, *_ = np.linalg.lstsq(feats, q, rcond=None)
    r2 = 1 - ((q - feats @ coef) ** 2).sum(0) / ((q - q.mean(0)) ** 2).sum(0)
    for o, name in enumerate(COLUMNS[2:]):
        if not r2[o] >= FOLLOW_R2:
            raise NnikError(f"{name} does not follow the position: a smooth map of x_um, y_um explains only "
                            f"{100 * max(r2[o], 0):.0f} % of its variance (need {100 * FOLLOW_R2:.0f} %); "
                            "are the columns in the order x_um,y_um,q1,q2 and from the same marks?", src)
    jac = coef[1:3] / np.sqrt((q - q.mean(0)) ** 2).mean(0)  # per output, normalised by its spread
    sv = np.linalg.svd(jac, compute_uv=False)
    if sv[1] < INDEPENDENT * sv[0]:
        raise NnikError("q1 and q2 move together (one is a scaled copy of the other): two motors that reach an "
                        "area move independently", src)


def network_weights(hidden, n_in: int = 2, n_out: int = 2) -> int:
    """The MLP's trainable parameters: each layer's weights and biases."""
    widths = [n_in, *hidden, n_out]
    return sum((a + 1) * b for a, b in zip(widths[:-1], widths[1:]))


def check_marks_for_network(mechanism, network: dict, source: str) -> None:
    """A measured machine's training rows hold two readings each; fewer readings than the
    network has weights leave the fit underdetermined."""
    if mechanism.analytic:
        return
    n = len(mechanism.positions_mm)
    train = split_sizes(n)["train"]
    weights = network_weights(network["hidden"])
    if 2 * train < weights:
        need = next(m for m in range(n, 100 * weights) if 2 * split_sizes(m)["train"] >= weights)
        raise NnikError(f"hidden {list(network['hidden'])} has {weights} weights but the {n} distinct marks leave "
                        f"{train} training rows, {2 * train} readings: measure at least {need} marks or use a "
                        "smaller [network] hidden", source, "[network] hidden")


def check_coverage(p_mm: np.ndarray, lo: np.ndarray, hi: np.ndarray, src: str) -> None:
    """Every cell of a coarse grid over the workspace must hold rows: a model fitted to a corner
    or a line of the workspace says nothing about the rest of it."""
    g = COVERAGE_GRID
    cell = np.clip(((p_mm - lo) / (hi - lo) * g).astype(np.int64), 0, g - 1)
    filled = np.zeros((g, g), dtype=bool)
    filled[cell[:, 1], cell[:, 0]] = True
    if not filled.all():
        empty = [(ix, iy) for iy in range(g) for ix in range(g) if not filled[iy, ix]]
        x0, y0 = lo + (hi - lo) * np.array(empty[0]) / g
        raise NnikError(
            f"the rows do not cover [workspace]: {len(empty)} of {g * g} cells of a {g}x{g} grid hold no "
            f"distinct measured position (the first from x={x0:g}, y={y0:g} mm); measure the whole "
            "workspace or shrink [workspace] to the data",
            src,
        )


def _noise_check(top: float):
    return lambda v: None if 0 <= v <= top else f"must be in [0, {top:g}], got {v}"


class Measured(Mechanism):
    kind = "measured"
    family = "measured"
    analytic = False
    PARAMS = {
        "csv": Param("str", required=True, doc="calibration CSV, relative to the TOML"),
        "reading_step": Param("float", default=0.0, check=_noise_check(1e6),
                              doc="q1/q2 are readings rounded to this step in actuator units (1: a step counter's "
                                  "whole microsteps; +-step/2 of rounding, variance step^2/12); 0: not rounded"),
        "noise_um": Param("float", default=0.0, check=_noise_check(1e4),
                          doc="measurement noise of x_um/y_um, 1 sigma per axis, if known (0: estimated)"),
    }

    def __init__(self, params, workspace, source="<scenario>"):
        super().__init__(params, workspace, source)
        self.csv_path = Path(params["csv"])
        p_mm, q = read_measurements(self.csv_path)
        lo, hi = workspace.lo, workspace.hi
        outside = np.any((p_mm < lo - 1e-9) | (p_mm > hi + 1e-9), axis=1)
        if outside.any():
            i = int(np.argmax(outside))
            raise NnikError(
                f"row {i + 1} at ({p_mm[i, 0]:.3f}, {p_mm[i, 1]:.3f}) mm lies outside [workspace]",
                str(self.csv_path),
            )
        # repeats kept, exact copies not: the repeats' spread is a noise estimate, a copy's is 0
        p_rows, q_rows, self.copies = drop_copies(p_mm, q)
        self.rows = (p_rows, q_rows)
        self.positions_mm, self.commands, _ = merge_duplicates(p_rows, q_rows)
        self.duplicates_merged = len(p_mm) - len(self.positions_mm)
        if len(self.positions_mm) < MIN_ROWS:
            raise NnikError(f"only {len(self.positions_mm)} distinct positions in {len(p_mm)} rows; need at least "
                            f"{MIN_ROWS}", str(self.csv_path))
        check_coverage(self.positions_mm, lo, hi, str(self.csv_path))
        check_readings(self.positions_mm, self.commands, str(self.csv_path))
        if self.copies:
            warnings.warn(NnikWarning(
                f"{self.csv_path}: {self.copies} of {len(p_mm)} rows repeat an earlier row exactly (position and "
                "readings): each counted once, and left out of the noise estimate"), stacklevel=2)

    def forward(self, q):
        raise NnikError("a measured mechanism has no analytic forward model", self.source, "[mechanism] kind")

    def inverse(self, p):
        raise NnikError("a measured mechanism has no analytic inverse model", self.source, "[mechanism] kind")
