"""Random machines nobody shipped (issue 15): random gimbal and two-mirror geometries over
asymmetric, off-centre fields, steppers and 12/16-bit DACs, and random belt frames (CoreXY and
HBOT with skew, bow, stretch, racking and pulley eccentricity). Wherever a float reference fit,
computed here, says a target is reachable in a few hundred bytes, the ladder reaches it, and the
family best it returns is bit-exact in C on the host.

CI draws a few machines (NNIK_HYPOTHESIS_MACHINES, default 3, and two thirds as many belt
frames); `make bench` draws more."""

from __future__ import annotations

import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nnik.bench.measured import BELT_DISTORTION, BELT_SPANS, belt_toml
from nnik.implementations.accuracy import accuracy
from nnik.selection import family_bests, fit_ladder
from tests.implementations.lut_helpers import host_check, problem_from

EXAMPLES = int(os.environ.get("NNIK_HYPOTHESIS_MACHINES", "3"))
FLOAT_DEGREE = 5  # the reference fit: a full bivariate polynomial of this degree, float64
TARGET_FLOOR = 0.05  # output units: what 16-bit Horner and int16 tables can promise on any field


@st.composite
def machines(draw):
    kind = draw(st.sampled_from(["galvo_gimbal", "galvo_dual"]))
    dist = draw(st.floats(120.0, 400.0))
    half = draw(st.floats(0.15, 0.35)) * dist  # the field's half-width, off-centre by up to 40 % of it
    cx, cy = (draw(st.floats(-0.4, 0.4)) * half for _ in range(2))
    aspect = draw(st.floats(0.5, 1.0))
    x = (round(cx - half, 1), round(cx + half, 1))
    y = (round(cy - half * aspect, 1), round(cy + half * aspect, 1))
    mech = (f'kind = "galvo_gimbal"\nz_mm = {dist:.1f}' if kind == "galvo_gimbal"
            else f'kind = "galvo_dual"\nd_mm = {dist:.1f}\ne_mm = {draw(st.floats(5.0, 20.0)):.1f}')
    act = draw(st.sampled_from(["stepper", "dac12", "dac16"]))
    if act == "stepper":
        actuator = 'kind = "stepper"\nsteps_per_rev = 200\nmicrosteps = 16'
        unit = ""
    else:
        actuator = f'kind = "dac"\nbits = {12 if act == "dac12" else 16}\noptical_range_deg = 60.0'
        unit = "[export]\ninput_unit_um = 0.25\n" if act == "dac16" else ""
    return (f'name = "rnd"\n[mechanism]\n{mech}\n[actuator]\n{actuator}\n[workspace]\nx_mm = [{x[0]}, {x[1]}]\n'
            f'y_mm = [{y[0]}, {y[1]}]\n{unit}')


@st.composite
def belt_frames(draw):
    """A CoreXY or HBOT frame, its distortion drawn from the ranges make bench's measured sweep uses."""
    dist = {k: draw(st.floats(lo, hi)) for k, (lo, hi) in BELT_DISTORTION.items()}
    return belt_toml("rnd", draw(st.sampled_from(["corexy", "hbot"])), draw(st.sampled_from(BELT_SPANS)), dist)


def float_reference_error(p) -> float:
    """Max error of a float64 least-squares polynomial of FLOAT_DEGREE over the domain."""
    def basis(pts):
        t = (pts - (p.lo + p.hi) / 2) / ((p.hi - p.lo) / 2)
        return np.stack([t[:, 0] ** i * t[:, 1] ** j for i in range(FLOAT_DEGREE + 1)
                         for j in range(FLOAT_DEGREE + 1 - i)], 1)
    g = [np.linspace(p.lo[a], p.hi[a], 81) for a in range(2)]
    fit = np.stack(np.meshgrid(*g, indexing="xy"), -1).reshape(-1, 2)
    coef, *_ = np.linalg.lstsq(basis(fit), p.truth(fit), rcond=None)
    chk = np.random.default_rng(1).integers(p.lo, p.hi + 1, (20_000, 2))
    return float(np.abs(basis(chk) @ coef - p.truth(chk)).max())


SETTINGS = dict(deadline=None, database=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                    HealthCheck.too_slow])


@settings(max_examples=EXAMPLES, **SETTINGS)
@given(text=machines())
def test_the_ladder_reaches_what_a_float_fit_reaches(tmp_path_factory, text):
    reaches(tmp_path_factory, text)


@settings(max_examples=max(1, (2 * EXAMPLES) // 3), **SETTINGS)
@given(text=belt_frames())
def test_the_ladder_reaches_what_a_float_fit_reaches_on_belt_frames(tmp_path_factory, text):
    reaches(tmp_path_factory, text)


def reaches(tmp_path_factory, text: str) -> None:
    """The property: a target twice the float fit's error is met by a family best of at most
    16 KB, that best's claim holds on the full check set, and its C is the integer model."""
    d = tmp_path_factory.mktemp("rnd")
    (d / "rnd.toml").write_text(text + f"[target]\nmax_error = 1.0\n")
    p = problem_from(d / "rnd.toml")
    target = max(2.0 * float_reference_error(p), TARGET_FLOOR)
    belt = p.scn.mechanism.kind in ("corexy", "hbot")
    cands = fit_ladder(p, ["poly", "lut", "hybrid"] if belt else ["poly", "lut"], max_error=target)
    bests = family_bests(cands, {"chip": "avr", "max_error": target})
    meeting = [c for c in bests.values() if c.meets(target)]
    assert meeting, (text, target, {f: c.acc.get("pre_max") for f, c in bests.items()})
    best = min(meeting, key=lambda c: c.est["avr"]["cycles"])
    assert best.est["avr"]["flash_bytes"] <= 16 * 1024
    # the accuracy claim holds on the full check set, and the C is the integer model
    assert accuracy(best.impl)["pre_max"] <= target
    r = host_check(best.impl, d)
    assert r["bit_exact"] and r["mismatches"] == 0, text
