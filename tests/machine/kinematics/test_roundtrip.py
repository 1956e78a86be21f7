"""FK(IK(p)) = p to 1e-9 mm over 1e5 random workspace points, for every analytic kind."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.machine.kinematics import KINDS, Workspace

N = 100_000
TOL_MM = 1e-9


def _points(ws: Workspace, seed: int) -> np.ndarray:
    return ws.lo + np.random.default_rng(seed).random((N, 2)) * (ws.hi - ws.lo)


def _roundtrip(mech, seed):
    p = _points(mech.workspace, seed)
    q = mech.inverse(p)
    err = np.abs(mech.forward(q) - p).max()
    assert err <= TOL_MM, err


@settings(max_examples=8, deadline=None)
@given(z=st.floats(50, 1000), half=st.floats(1, 400), seed=st.integers(0, 2**31))
def test_gimbal_roundtrip(z, half, seed):
    half = min(half, 0.9 * z)
    ws = Workspace((-half, half), (-half, half))
    _roundtrip(KINDS["galvo_gimbal"]({"z_mm": z, "max_mech_deg": 45.0}, ws), seed)


@settings(max_examples=8, deadline=None)
@given(d=st.floats(50, 500), e=st.floats(0, 30), frac=st.floats(0.05, 0.6), seed=st.integers(0, 2**31))
def test_dual_roundtrip(d, e, frac, seed):
    ws = Workspace((-frac * d, frac * d), (-frac * d, frac * d))
    _roundtrip(KINDS["galvo_dual"]({"d_mm": d, "e_mm": e, "max_mech_deg": 45.0}, ws), seed)


distortions = st.fixed_dictionaries({
    "A_deg": st.floats(85, 95),
    "B_deg": st.floats(-5, 5),
    "bow_mm": st.floats(-0.5, 0.5),
    "stretch": st.floats(-0.01, 0.01),
    "racking_deg": st.floats(-0.3, 0.3),
    "eccentricity_mm": st.floats(0, 0.05),
    "eccentricity_phase_deg": st.floats(0, 360),
})


@settings(max_examples=6, deadline=None)
@given(kind=st.sampled_from(["hbot", "corexy"]), dist=distortions, r=st.floats(4, 12), seed=st.integers(0, 2**31))
def test_belt_roundtrip_with_distortion(kind, dist, r, seed):
    params = {"R1_mm": r, "R2_mm": r * 1.01, "distortion": dist}
    if kind == "hbot":
        params |= {"X_mm": 400.0, "C_mm": 60.0}
    ws = Workspace((0.0, 300.0), (0.0, 250.0))
    _roundtrip(KINDS[kind](params, ws), seed)
