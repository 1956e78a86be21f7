"""Klipper's resonance test logs, read and checked: the raw accelerometer CSV
(raw_data_<axis>_*.csv: a header line `#time,accel_x,accel_y,accel_z`, then one sample a line,
mm/s^2) and the processed PSD (resonances_<axis>_*.csv: `freq,psd_x,psd_y,psd_z,psd_xyz`, with
`,shapers:,...` columns after them when SHAPER_CALIBRATE wrote it; then the PSD is already
normalised, as Klipper's calibrate_shaper.py reads it).

Every problem is one CalibrationError line: empty, binary, another header, a short or
non-numeric row, time not increasing, too few samples, a clipped accelerometer (its extreme
value held by CLIP_MIN samples and CLIP_PILE times as many as the next value in: what lay beyond
the rail piled up on it), or a PSD that is negative or not over increasing frequencies.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nnik.dynamics.calibrate import CalibrationError

RAW = ("time", "accel_x", "accel_y", "accel_z")
PSD = ("freq", "psd_x", "psd_y", "psd_z", "psd_xyz")
MIN_RAW_S = 5.0
MIN_RATE_HZ = 100.0
CLIP_MIN, CLIP_PILE, CLIP_LEVELS = 20, 3.0, 16
MAX_BYTES = 1 << 30
NAME = re.compile(r"(?:raw_data|resonances)_([a-z])_", re.I)


@dataclass
class ResonanceLog:
    kind: str  # "raw" or "psd"
    rows: np.ndarray  # raw: (N, 4) time, ax, ay, az; psd: (N, 5) freq, x, y, z, sum
    normalized: bool  # psd only: Klipper's normalisation already applied
    axis: str | None  # from the file name (raw_data_x_..., resonances_y_...), else None


def axis_of(path: Path) -> str | None:
    m = NAME.match(path.name)
    return m.group(1).lower() if m else None


def _rows(lines: list[tuple[int, str]], ncols: int, extra_ok: bool) -> np.ndarray:
    if not extra_ok:  # the common case at numpy's speed; any problem is then found line by line
        try:
            out = np.loadtxt([ln for _, ln in lines], delimiter=",", ndmin=2, dtype=float)
            if out.shape[1:] == (ncols,) and np.isfinite(out).all():
                return out
        except ValueError:
            pass
    cells = []
    for no, ln in lines:
        parts = ln.split(",")
        if len(parts) < ncols or (len(parts) > ncols and not extra_ok):
            raise CalibrationError(f"line {no}: {len(parts)} columns, expected {ncols}")
        cells.append(parts[:ncols])
    try:
        out = np.array(cells, dtype=float).reshape(-1, ncols)
    except ValueError:
        for (no, _), row in zip(lines, cells):
            for v in row:
                try:
                    float(v)
                except ValueError:
                    raise CalibrationError(f"line {no}: {v.strip()[:40]!r} is not a number") from None
        raise
    bad = ~np.isfinite(out).all(axis=1)
    if bad.any():
        raise CalibrationError(f"line {lines[int(np.argmax(bad))][0]}: a value is not finite")
    return out


def read_log(path: str | Path) -> ResonanceLog:
    path = Path(path)
    if path.is_dir():
        raise CalibrationError("a directory, not a resonance test log")
    if not path.is_file():
        raise CalibrationError("file not found")
    if path.stat().st_size > MAX_BYTES:
        raise CalibrationError(f"{path.stat().st_size} bytes: larger than any resonance test log (1 GiB)")
    data = path.read_bytes()
    if not data.strip():
        raise CalibrationError("empty file: expected Klipper's resonance CSV (#time,accel_x,accel_y,accel_z or "
                               "freq,psd_x,psd_y,psd_z,psd_xyz)")
    if b"\0" in data:
        raise CalibrationError("a binary file, not Klipper's resonance CSV")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise CalibrationError("not text (not UTF-8): a binary file, not Klipper's resonance CSV") from None
    lines = [(i + 1, ln.strip()) for i, ln in enumerate(text.splitlines()) if ln.strip()]
    head_no, head = lines[0]
    names = tuple(c.strip() for c in head.lstrip("#").split(","))
    body = [(no, ln) for no, ln in lines[1:] if not ln.startswith("#")]
    if head.startswith("#") and names == RAW:
        return _raw(_rows(body, 4, False), path)
    if names[:5] == PSD:
        return _psd(_rows(body, 5, True), "mzv" in head, path)
    raise CalibrationError(f"line {head_no}: header {head[:60]!r}; expected Klipper's raw accelerometer header "
                           "'#time,accel_x,accel_y,accel_z' or the processed 'freq,psd_x,psd_y,psd_z,psd_xyz'")


def _raw(rows: np.ndarray, path: Path) -> ResonanceLog:
    if len(rows) < 2:
        raise CalibrationError(f"too short: {len(rows)} samples")
    t = rows[:, 0]
    step = np.diff(t)
    if (step <= 0).any():
        k = int(np.argmax(step <= 0))
        raise CalibrationError(f"time does not increase at sample {k + 2} ({t[k]:.6f} then {t[k + 1]:.6f} s)")
    span = float(t[-1] - t[0])
    rate = (len(t) - 1) / span
    if span < MIN_RAW_S:
        raise CalibrationError(f"too short: {span:.2f} s of samples; at least {MIN_RAW_S:g} s are needed (Klipper's "
                               "test sweeps for about 2 minutes)")
    if rate < MIN_RATE_HZ:
        raise CalibrationError(f"{rate:.0f} samples a second: too few to see resonances (at least {MIN_RATE_HZ:g})")
    for k, name in enumerate(RAW[1:], start=1):
        held = _clipped(rows[:, k])
        if held is not None:
            raise CalibrationError(f"{name} is clipped: {held[0]} samples sit at its extreme ({held[1]:.1f} mm/s^2), "
                                   f"{CLIP_PILE:g} x more than at the next value in; lower accel_per_hz or use the "
                                   "accelerometer's wider range")
    return ResonanceLog("raw", rows, False, axis_of(path))


def _clipped(x: np.ndarray) -> tuple[int, float] | None:
    """(count, value) of an extreme that holds CLIP_MIN samples and CLIP_PILE times as many as the
    next value in (values beyond a rail pile up on it; a quantised signal that merely peaks
    there thins out instead), on a column with at least CLIP_LEVELS distinct values; else None."""
    vals, counts = np.unique(x, return_counts=True)
    if len(vals) < CLIP_LEVELS:
        return None
    for end, nxt in ((-1, -2), (0, 1)):
        if counts[end] >= CLIP_MIN and counts[end] > CLIP_PILE * counts[nxt]:
            return int(counts[end]), float(vals[end])
    return None


def _psd(rows: np.ndarray, normalized: bool, path: Path) -> ResonanceLog:
    if len(rows) < 16:
        raise CalibrationError(f"too short: {len(rows)} frequency bins (Klipper writes one every ~1.6 Hz to 200 Hz)")
    if (np.diff(rows[:, 0]) <= 0).any():
        raise CalibrationError("the frequencies do not increase")
    if (rows[:, 1:] < 0).any():
        raise CalibrationError("a power spectral density is negative")
    return ResonanceLog("psd", rows, normalized, axis_of(path))
