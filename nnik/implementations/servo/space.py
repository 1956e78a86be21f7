"""The search space of each controller's gains: pole placement on each axis' identified model.

Each axis' model is speed = K * volts through tau: in duty, x'' tau + x' = g u with
g = K supply / duty_max (counts/s per duty). A PD u = kp e + kd e' places the closed loop's poles at
tau s^2 + (1 + g kd) s + g kp = 0, so for a natural frequency wn and damping zeta per axis:

    kp = tau wn^2 / g,   kd = max(0, 2 zeta tau wn - 1) / g
    ki = kp wn / r                    (an integral time r / wn; PID and the CCC's axes)
    kv = m_v / g,  ka = m_a tau / g   (the exact speed and acceleration feedforwards, times m_v, m_a)
    kcp = m_c mean(kp),  kcd = m_cd kcp mean(tau)     (the CCC's contour loop)

The trial draws per axis wn (log, 0.02 .. 0.5 / tick: the discrete loop's reach), zeta (log,
0.3 .. 10: up to a near first-order, overdamped response), r (log, 1 .. 1e5: down to almost no integral), m_v, m_a
(0 .. 1.5), and for the CCC m_c (log, 0.001 .. 10: down to no cross-coupling) and m_cd (log,
0.01 .. 10). Matching the axes is left to the search (and, for the contour, to the CCC). A gain beyond its
fixed-point format is clipped to the format's top, and every gain is returned as the value the chip
runs (quantised, then converted back to physical units), so the tuned gains are exact.
"""

from __future__ import annotations

from nnik.implementations.servo import fixed as fx

WN_TICKS = (0.02, 0.5)  # wn * tick
ZETA = (0.3, 10.0)
R_INT = (1.0, 1e5)
M_FF = (0.0, 1.5)
M_C = (0.001, 10.0)
M_CD = (0.01, 10.0)
# gain -> (fraction bits, the physical value's scale to its quantised unit)
FORMATS = {"kp": (fx.Q_GAIN, lambda t, w: 1.0), "kcp": (fx.Q_GAIN, lambda t, w: 1.0),
           "ki": (fx.Q_INT, lambda t, w: t), "kd": (fx.Q_GAIN, lambda t, w: 1.0 / t),
           "kcd": (fx.Q_GAIN, lambda t, w: 1.0 / t), "kv": (fx.Q_GAIN, lambda t, w: 1.0 / (w * t)),
           "ka": (fx.Q_GAIN, lambda t, w: 1.0 / (w * t) ** 2)}


def chip_value(name: str, value: float, tick_s: float, win: int) -> float:
    """value clipped to its format and rounded to what the chip runs, in physical units."""
    bits, unit = FORMATS[name.split("_")[0]]
    s = unit(tick_s, win) * (1 << bits)
    q = min(fx.U16, max(0, round(value * s)))
    return q / s


def gains_for(kind: str, cfg, models, p: dict, win: int = 4) -> dict:
    """The gains of the design parameters p (wn, zeta, and r / m_v, m_a / m_c, m_cd by kind)."""
    g = {}
    for a, m in zip(("x", "y"), models):
        wn, zeta = p[f"wn_{a}"], p[f"zeta_{a}"]
        gain = m.k_counts_s_v * cfg.supply_v / cfg.duty_max
        tau = m.tau_s
        g[f"kp_{a}"] = tau * wn * wn / gain
        g[f"kd_{a}"] = max(0.0, 2 * zeta * tau * wn - 1.0) / gain
        if kind in ("pid", "ccc"):
            g[f"ki_{a}"] = g[f"kp_{a}"] * wn / p[f"r_{a}"]
        else:
            g[f"kv_{a}"] = p[f"m_v_{a}"] / gain
            g[f"ka_{a}"] = p[f"m_a_{a}"] * tau / gain
    if kind == "ccc":
        g["kcp"] = p["m_c"] * (g["kp_x"] + g["kp_y"]) / 2
        g["kcd"] = p["m_cd"] * g["kcp"] * (models[0].tau_s + models[1].tau_s) / 2
    return {k: chip_value(k, v, cfg.tick_s, win) for k, v in g.items()}


def suggest(kind: str, trial, cfg, models, win: int = 4) -> dict:
    """One trial's gains for kind."""
    t = cfg.tick_s
    p = {}
    for a in ("x", "y"):
        p[f"wn_{a}"] = trial.suggest_float(f"wn_{a}", WN_TICKS[0] / t, WN_TICKS[1] / t, log=True)
        p[f"zeta_{a}"] = trial.suggest_float(f"zeta_{a}", *ZETA, log=True)
        if kind in ("pid", "ccc"):
            p[f"r_{a}"] = trial.suggest_float(f"r_{a}", *R_INT, log=True)
        else:
            p[f"m_v_{a}"] = trial.suggest_float(f"m_v_{a}", *M_FF)
            p[f"m_a_{a}"] = trial.suggest_float(f"m_a_{a}", *M_FF)
    if kind == "ccc":
        p["m_c"] = trial.suggest_float("m_c", *M_C, log=True)
        p["m_cd"] = trial.suggest_float("m_cd", *M_CD, log=True)
    return gains_for(kind, cfg, models, p, win)


START_WN_TAU = (1.0, 2.0, 4.0)  # the enqueued starts' wn, times 1 / tau


def start_points(kind: str, cfg, models) -> list[dict[str, float]]:
    """The trials enqueued first (part of the budget): per axis wn = 1, 2 and 4 / tau (within the
    range), critically damped, a slow integral (time 3000 / wn), the feedforwards exact; the contour
    loop as strong as the axes'."""
    t = cfg.tick_s
    out = []
    for f in START_WN_TAU:
        p = {}
        for a, m in zip(("x", "y"), models):
            p[f"wn_{a}"] = min(WN_TICKS[1] / t, max(WN_TICKS[0] / t, f / m.tau_s))
            p[f"zeta_{a}"] = 1.0
            if kind in ("pid", "ccc"):
                p[f"r_{a}"] = 3000.0
            else:
                p.update({f"m_v_{a}": 1.0, f"m_a_{a}": 1.0})
        if kind == "ccc":
            p.update(m_c=1.0, m_cd=1.0)
        out.append(p)
    return out
