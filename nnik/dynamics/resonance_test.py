"""A resonance log as Klipper's TEST_RESONANCES writes it, measured on a simulated axis: the test
logs of `nnik shaper-calibrate` and its sample data.

The test (Klipper's resonance_tester, its vibration test): from f_start to f_end the toolhead
accelerates at +-accel_per_hz * f for quarter periods 1 / (4 f), in the pattern +a, -a, -a, +a
(a square wave of acceleration at f, the velocity a triangle wave around zero), f rising by
hz_per_sec each second.  Klipper's defaults of that form: 5 to 133.33 Hz, 75 mm/s^2 per Hz,
1 Hz/s.  Half a second at rest comes before it, as Klipper dwells.

The axis: the base-excited spring-damper of nnik.dynamics.axis (the tip is where the
accelerometer sits); its transfer function is the same from base to tip acceleration, so the
tip's acceleration is tip() of the base's, on a grid OVERSAMPLE times finer than the
accelerometer's (the square wave's edges fall between samples), then read at its sample times.

The accelerometer: rate_hz samples (an ADXL345 at 3200 Hz by default), noise_mm_s2 (1 sigma)
on each axis, quantised to lsb_mm_s2 (3.9 mg: the ADXL345's full-resolution step), mounted
tilt_deg off the axis (a part of the motion shows on the other horizontal axis), gravity on Z.

    python3 -m nnik.dynamics.resonance_test OUT.csv --f-hz 42 --zeta 0.08 [--axis x] [--seed 0]
writes a raw_data CSV (#time,accel_x,accel_y,accel_z, as Klipper's "%.6f" columns);
--processed writes the processed form instead (freq,psd_x,psd_y,psd_z,psd_xyz), as
TEST_RESONANCES writes resonances_<axis>_*.csv.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from nnik.dynamics.axis import tip

F_START, F_END, ACCEL_PER_HZ, HZ_PER_SEC = 5.0, 133.33, 75.0, 1.0
RATE_HZ = 3200.0
LSB_MM_S2 = 3.9e-3 * 9806.65
GRAVITY_MM_S2 = 9806.65
OVERSAMPLE = 16
DWELL_S = 0.5


def test_sequence(f_start=F_START, f_end=F_END, accel_per_hz=ACCEL_PER_HZ, hz_per_sec=HZ_PER_SEC):
    """(ends (s), accel (mm/s^2)): the acceleration held until each end, from t = 0."""
    ends, acc = [], []
    f, sign, t = f_start, 1.0, 0.0
    while f <= f_end + 1e-6:
        q = 0.25 / f
        a = accel_per_hz * f
        ends += [t + q, t + 2 * q]
        acc += [sign * a, -sign * a]
        t += 2 * q
        f += 2 * q * hz_per_sec
        sign = -sign
    return np.array(ends), np.array(acc)


def tip_accel(f_hz: float, zeta: float, rate_hz: float = RATE_HZ, **test) -> tuple[np.ndarray, np.ndarray]:
    """(sample times from the start of the dwell, the tip's acceleration there) for the test."""
    ends, acc = test_sequence(**test)
    dt = 1.0 / (rate_hz * OVERSAMPLE)
    n = int(math.ceil((DWELL_S + ends[-1] + 0.5) * rate_hz)) * OVERSAMPLE
    mid = (np.arange(n) + 0.5) * dt - DWELL_S  # each fine interval's input: the base at its middle
    k = np.searchsorted(ends, mid, side="right")
    base = np.where((mid >= 0) & (k < len(acc)), acc[np.minimum(k, len(acc) - 1)], 0.0)
    out = tip(base, dt, f_hz, zeta)
    return np.arange(0, n, OVERSAMPLE) * dt, out[::OVERSAMPLE]


def raw_log(f_hz: float, zeta: float, seed: int = 0, rate_hz: float = RATE_HZ, noise_mm_s2: float = 60.0,
            lsb_mm_s2: float = LSB_MM_S2, tilt_deg: float = 4.0, axis: str = "x", t0: float = 1234.5,
            **test) -> np.ndarray:
    """(N, 4) rows time, accel_x, accel_y, accel_z of the test on an axis (f_hz, zeta)."""
    t, a = tip_accel(f_hz, zeta, rate_hz, **test)
    rng = np.random.default_rng(seed)
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    along, across = (c * a, s * a)
    xy = (along, across) if axis == "x" else (across, along)
    cols = [xy[0], xy[1], np.full_like(a, GRAVITY_MM_S2)]
    cols = [v + rng.normal(0.0, noise_mm_s2, len(v)) for v in cols]
    if lsb_mm_s2:
        cols = [np.round(v / lsb_mm_s2) * lsb_mm_s2 for v in cols]
    return np.column_stack([t0 + t, *cols])


def write_raw(path, rows: np.ndarray) -> None:
    np.savetxt(path, rows, fmt="%.6f", delimiter=",", header="#time,accel_x,accel_y,accel_z", comments="")


def write_processed(path, freqs: np.ndarray, psd: np.ndarray) -> None:
    """psd: (N, 4) x, y, z, sum, as TEST_RESONANCES writes them (not normalised)."""
    rows = np.column_stack([freqs, psd])
    keep = freqs < 200.0
    with open(path, "w") as f:
        f.write("freq,psd_x,psd_y,psd_z,psd_xyz\n")
        for r in rows[keep]:
            f.write(f"{r[0]:.1f}," + ",".join(f"{v:.3e}" for v in r[1:]) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m nnik.dynamics.resonance_test",
                                 description="Write the CSV Klipper's resonance test would log on a simulated axis.")
    ap.add_argument("output")
    ap.add_argument("--f-hz", type=float, required=True, help="the axis's natural frequency")
    ap.add_argument("--zeta", type=float, required=True, help="its damping ratio")
    ap.add_argument("--axis", choices=("x", "y"), default="x")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--noise", type=float, default=60.0, help="accelerometer noise, mm/s^2 (1 sigma)")
    ap.add_argument("--rate-hz", type=float, default=RATE_HZ)
    ap.add_argument("--freq-start", type=float, default=F_START)
    ap.add_argument("--freq-end", type=float, default=F_END)
    ap.add_argument("--hz-per-sec", type=float, default=HZ_PER_SEC)
    ap.add_argument("--processed", action="store_true", help="write the PSD form (resonances_<axis>_*.csv)")
    a = ap.parse_args(argv)
    if not (0 < a.f_hz < a.rate_hz / 4 and 0 <= a.zeta < 1 and a.noise >= 0 and 0 < a.freq_start < a.freq_end):
        print("resonance_test: error: need 0 < f < rate/4, 0 <= zeta < 1, noise >= 0, freq-start < freq-end",
              file=sys.stderr)
        return 2
    rows = raw_log(a.f_hz, a.zeta, a.seed, a.rate_hz, a.noise, axis=a.axis, f_start=a.freq_start,
                   f_end=a.freq_end, hz_per_sec=a.hz_per_sec)
    if a.processed:
        from nnik.dynamics.calibrate import klipper_spectrum

        sp = klipper_spectrum(rows)
        write_processed(a.output, sp.freqs, sp.psd)
    else:
        write_raw(a.output, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
