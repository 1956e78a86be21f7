"""A DC-servo log, read and checked: the CSV that `nnik identify` fits.

Format: a header line naming the columns, then one sample a line, comma-separated:

    t,u_x,u_y,count_x,count_y
    0.000,0.0,0.0,40000,30000
    0.005,7.2,-5.9,40000,30000
    ...

- t: time in seconds, increasing with a uniform step (the controller's tick). A step may differ
  from the median step by at most STEP_TOLERANCE (10 %): a log is never resampled, since the fit is
  a discrete model at one tick. The tick is the median step.
- u_x, u_y: what was applied from that sample to the next (zero-order hold), in volts; with
  `supply_v` given (identify --supply V) they are duty fractions in [-1, 1] instead (duty /
  DUTY_MAX; sign = direction), converted to volts as duty * supply_v.
- count_x, count_y: the encoder counts at that sample (before u acts). Counts of an 8-bit counter
  (0..255, wrapping; the seed's rig) are unwrapped with `counts8=True` (identify --counts8): each
  step is taken as the signed 8-bit difference, so an axis must move less than 128 counts a tick.
  Without it, integer counts that stay within 0..255 and jump by more than 128 between samples
  are refused (a wrapping counter read as positions).
- Columns may come in any order and more may follow (ignored); blank lines and lines starting with
  '#' after the header are skipped; line ends may be LF, CRLF or CR alone.

Every problem is one ServoError line naming it: no file, empty, binary, no header or missing
columns, a short or non-numeric row, NaN or infinity, time not increasing or not uniform, too few
samples (MIN_SAMPLES), a duty outside [-1, 1]. What the fit needs of the data (excitation, motion,
no saturation) is judged per axis by nnik.dynamics.servo.fit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nnik.dynamics.servo.servo_error import ServoError
from nnik.dynamics.text_log import numbered_lines

COLUMNS = ("t", "u_x", "u_y", "count_x", "count_y")
MIN_SAMPLES = 100  # 0.5 s at the 5 ms tick; a fit of 4 parameters needs far more than 4 samples
STEP_TOLERANCE = 0.10  # a time step may differ this much from the median (relative)
MAX_BYTES = 1 << 30


@dataclass(frozen=True)
class ServoLog:
    t: np.ndarray  # (N,) s
    volts: np.ndarray  # (N, 2) V, held from each sample to the next
    counts: np.ndarray  # (N, 2) encoder counts (unwrapped), float
    tick_s: float  # the median time step
    duty: np.ndarray | None  # (N, 2) duty fractions when the log gave duties (--supply), else None


def _lines(path: Path) -> list[tuple[int, str]]:
    return numbered_lines(path, "a servo log CSV (header t,u_x,u_y,count_x,count_y)", MAX_BYTES, ServoError)


def _columns(head_no: int, head: str) -> list[int]:
    names = [c.strip().lower() for c in head.lstrip("#").split(",")]
    missing = [c for c in COLUMNS if c not in names]
    if missing:
        raise ServoError(f"line {head_no}: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
                        f"(header {head[:60]!r}; a servo log needs {','.join(COLUMNS)})")
    return [names.index(c) for c in COLUMNS]


def _table(body: list[tuple[int, str]], cols: list[int]) -> np.ndarray:
    width = max(cols) + 1
    out = np.empty((len(body), len(cols)))
    for r, (no, ln) in enumerate(body):
        parts = ln.split(",")
        if len(parts) < width:
            raise ServoError(f"line {no}: {len(parts)} columns, the header names {width} or more")
        for c, k in enumerate(cols):
            try:
                v = float(parts[k])
            except ValueError:
                raise ServoError(f"line {no}: {COLUMNS[c]} = {parts[k].strip()[:40]!r} is not a number") from None
            if not np.isfinite(v):
                raise ServoError(f"line {no}: {COLUMNS[c]} is {parts[k].strip()}, not a finite number")
            out[r, c] = v
    return out


def _tick(t: np.ndarray) -> float:
    step = np.diff(t)
    if (step <= 0).any():
        k = int(np.argmax(step <= 0))
        raise ServoError(f"time does not increase at sample {k + 2} ({t[k]:.6g} then {t[k + 1]:.6g} s)")
    tick = float(np.median(step))
    off = np.abs(step / tick - 1.0)
    if off.max() > STEP_TOLERANCE:
        k = int(np.argmax(off))
        raise ServoError(f"time step not uniform: {step[k]:.6g} s at sample {k + 2} against the median {tick:.6g} s "
                        f"(at most {100 * STEP_TOLERANCE:g} % apart; the fit is a discrete model at one tick, so nnik "
                        "does not resample)")
    return tick


def unwrap8(raw: np.ndarray, name: str) -> np.ndarray:
    """An 8-bit counter's readings as a position: cumulative signed 8-bit differences."""
    if ((raw < 0) | (raw > 255) | (raw != np.round(raw))).any():
        k = int(np.argmax((raw < 0) | (raw > 255) | (raw != np.round(raw))))
        raise ServoError(f"{name} = {raw[k]:g} at sample {k + 1}: --counts8 reads 8-bit counter values 0..255")
    d = (np.diff(raw.astype(np.int64)) + 128) % 256 - 128
    return np.concatenate([[raw[0]], raw[0] + np.cumsum(d)]).astype(float)


def _looks_wrapped(c: np.ndarray) -> bool:
    return bool(((c >= 0) & (c <= 255) & (c == np.round(c))).all() and (np.abs(np.diff(c)) > 128).any())


def read_servo_log(path: str | Path, supply_v: float | None = None, counts8: bool = False) -> ServoLog:
    lines = _lines(Path(path))
    head_no, head = lines[0]
    cols = _columns(head_no, head)
    body = [(no, ln) for no, ln in lines[1:] if not ln.startswith("#")]
    if len(body) < MIN_SAMPLES:
        raise ServoError(f"too short: {len(body)} samples; identification needs at least {MIN_SAMPLES}")
    rows = _table(body, cols)
    t = rows[:, 0]
    tick = _tick(t)
    counts = rows[:, 3:5].copy()
    for a, name in enumerate(COLUMNS[3:]):
        if counts8:
            counts[:, a] = unwrap8(counts[:, a], name)
        elif _looks_wrapped(counts[:, a]):
            raise ServoError(f"{name} stays within 0..255 and jumps by more than 128 between samples: an 8-bit counter "
                            "that wraps? give --counts8 to unwrap it")
    u = rows[:, 1:3]
    duty = None
    if supply_v is not None:
        if (np.abs(u) > 1.0).any():
            r, c = np.argwhere(np.abs(u) > 1.0)[0]
            raise ServoError(f"line {body[r][0]}: {COLUMNS[1 + c]} = {u[r, c]:g}: with --supply the u columns are duty "
                            "fractions in [-1, 1]")
        duty, u = u, u * supply_v
    return ServoLog(t, u, counts, tick, duty)
