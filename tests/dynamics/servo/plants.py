"""Random DC-servo plants for the plant's tests: the class's range and well beyond it, each one
that the scenario check accepts (its substeps resolve both time constants)."""

from __future__ import annotations

import math
from dataclasses import replace

from hypothesis import strategies as st

from nnik.dynamics.servo.config import MotorAxis, ServoConfig
from nnik.machine.servo import servo_problems


@st.composite
def motor_axes(draw, coulomb: bool = True, stiction: bool = False, backlash: bool = False) -> MotorAxis:
    ra = draw(st.floats(0.5, 10.0))
    ke = draw(st.floats(0.004, 0.05))
    tau_e = draw(st.floats(2e-4, 2e-3))
    tau_m = draw(st.floats(0.02, 0.2))
    b = draw(st.floats(0.0, 2e-6))
    j = tau_m * (ke * ke + ra * b) / ra
    stall = ke * 12.0 / ra
    tc = draw(st.floats(0.0, 0.3)) * stall if coulomb else 0.0
    ts = tc + draw(st.floats(0.01, 0.4)) * stall if stiction else 0.0
    if ts >= 0.9 * stall:
        ts = 0.9 * stall
    return MotorAxis(ra_ohm=ra, la_h=tau_e * ra, ke_v_s_rad=ke, j_kg_m2=j, viscous_n_m_s_rad=b,
                     coulomb_n_m=tc, stiction_n_m=ts,
                     backlash_um=draw(st.floats(1.0, 100.0)) if backlash else 0.0,
                     gear_ratio=draw(st.sampled_from([1.0, 18.75, 30.0, 50.0])))


@st.composite
def configs(draw, encoder: str = "quadrature", **axis_kw) -> ServoConfig:
    axes = (draw(motor_axes(**axis_kw)), draw(motor_axes(**axis_kw)))
    cfg = ServoConfig(axes=axes, tick_s=0.005, supply_v=12.0, duty_max=255, encoder=encoder, substeps=1,
                      counts_per_rev=1200, lead_mm=3.0)
    tau = min(min(ax.tau_e_s, ax.tau_m_s / 20) for ax in axes)
    cfg = replace(cfg, substeps=max(4, math.ceil(cfg.tick_s / tau)))
    assert servo_problems(cfg) == [] or encoder == "counter8"
    return cfg
