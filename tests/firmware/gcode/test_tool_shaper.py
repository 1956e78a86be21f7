"""The tool's shaper (nnik_sh_tool, modelled in bulk by nnik.firmware.gcode.tool_shaper): the bulk
model equals the chip's loop, transliterated here sample by sample (with its 16-bit wraps)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.dynamics.shapers import KINDS
from nnik.firmware.config import shaper_taps
from nnik.firmware.gcode.tool_shaper import shaped_duty


def chip_loop(pd, v, m4, taps, length):
    """nnik_sh_tool as written in C, one sample at a time."""
    R = length + 1
    ds_r, pd_r = [0] * R, [0] * R
    amps, delays = taps
    u = [0] * len(amps)
    lag_prev = e = k = tat = 0
    out = []
    for p, vv, f in zip(pd, v, m4):
        ds = (vv + 0x7FFF) >> 15
        tat = 0 if tat + 1 == R else tat + 1
        ds_r[tat], pd_r[tat] = ds | (0x8000 if f else 0), p
        s = 16384
        for i, (A, d) in enumerate(zip(amps, delays)):
            if d:
                u[i] = (u[i] + ds - (ds_r[(tat - d) % R] & 0x7FFF)) & 0xFFFF
                s += A * u[i]
        lag = (s >> 15) & 0xFFFF
        k, e = k + 1, (e + ds) & 0xFFFF
        while k > length or e > lag:
            k -= 1
            e = (e - (ds_r[(tat - k) % R] & 0x7FFF)) & 0xFFFF
        vs = ds - lag + lag_prev
        lag_prev = lag
        j = (tat - k) % R
        d = pd_r[j]
        if ds_r[j] & 0x8000 and ds_r[j] & 0x7FFF:
            d = min(255, d * vs // (ds_r[j] & 0x7FFF) if vs > 0 else 0)
        out.append(d)
    return np.array(out, dtype=np.int64)


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(KINDS), f=st.floats(25, 90), zeta=st.floats(0.0, 0.2), hz=st.sampled_from([500, 1000]),
       seed=st.integers(0, 2**31), vmax=st.integers(1, 200))
def test_bulk_model_equals_the_chips_loop(kind, f, zeta, hz, seed, vmax):
    taps = shaper_taps(kind, {"f_hz": (f, f), "zeta": (zeta, zeta)}, hz)[0]
    length = max(taps[1])
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 400))
    # runs of speeds: rests, ramps, cruise, with random duties and M4 flags per run
    v = np.repeat(rng.integers(0, vmax << 16, 12), rng.integers(1, 60, 12))[:n]
    v[rng.random(len(v)) < 0.2] = 0
    n = len(v)
    pd = np.repeat(rng.integers(0, 256, 12), rng.integers(1, 60, 12))[:n]
    pd = np.resize(pd, n)
    m4 = np.resize(np.repeat(rng.integers(0, 2, 12), rng.integers(1, 60, 12)), n)
    assert np.array_equal(shaped_duty(pd, v, m4, taps, length), chip_loop(pd, v, m4, taps, length))
