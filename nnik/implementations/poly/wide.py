"""The `poly` family's wide path (``width = 32``): the same Horner program one size up, for fields
where 16-bit evaluation limits the accuracy (a 16-bit DAC gimbal: its outputs span 2^16 LSB, and
int16 intermediates round at about 2^-15 of it).

* Inputs: ``u = x - c`` unshifted in int32 (the normalised input ``t = u / 2^(15 + k)``, the same
  t the 16-bit path rounds to ``u >> k``): the polynomial is fitted in the exact t, and no
  dropped-bits correction is needed.
* Values and constants int32, products exact in 64 bits, exponents by the same range analysis
  and interval proof (``nnik.implementations.poly.int_model`` with ``width=32``); the outputs'
  sums stay int32.
* C: ``codegen/templates/poly32_ik.c.j2``: on avr-gcc the 32 x 32 -> 64 product column by
  column on the hardware multiplier (16 MUL in one asm block), the byte pick and the last
  0..7-bit shift of each call inlined; SDCC pic16 (no 64-bit type): 16 MULWF in one __asm
  block on a work area, shifts bytewise; the host: four 16 x 16 -> 32 partial products in two
  32-bit halves.
* Cost: a linear model in the C's structure (calls, shift bits, byte picks, the operands' signs,
  the outputs' shifts: nnik.implementations.poly.wide_cost), calibrated on simavr / gpsim
  (``nnik/calibration/poly32.json``, ``python -m nnik.bench.poly32_calibration``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnik.implementations.c_common import i32
from nnik.implementations.cost_band import stated_band
from nnik.implementations.poly import int_model as poly_int

WIDTH = 32
CALIBRATION = Path(__file__).resolve().parents[2] / "calibration" / "poly32.json"


def urange(impl) -> list[tuple[int, int]]:
    p = impl.problem
    return [(int(p.lo[a]) - impl.maps[a].c, int(p.hi[a]) - impl.maps[a].c) for a in range(2)]


def exponents(impl) -> list[int]:
    """The inputs' exponents: t = u / 2^(15 + k)."""
    return [15 + m.k for m in impl.maps]


def build(impl, grid: int) -> None:
    """The proven int32 program of impl's fitted coefficients (impl.plans, impl.prog)."""
    ur, e = urange(impl), exponents(impl)
    gx = np.unique(np.rint(np.linspace(*ur[0], grid)))
    gy = np.unique(np.rint(np.linspace(*ur[1], grid)))
    tx, ty = np.meshgrid(gx / 2.0 ** e[0], gy / 2.0 ** e[1], indexing="xy")
    env = {"u": tx.ravel(), "v": ty.ravel(), "e_u": e[0], "e_v": e[1]}
    poly_int.Node._n = 0  # deterministic names, hence a deterministic C text
    u, v = poly_int.Node("in", name="u"), poly_int.Node("in", name="v")
    shared = {"u": u, "v": v, "u2": poly_int.Node("mac", u, u, name="u2"),
              "v2": poly_int.Node("mac", v, v, name="v2"), "uv": poly_int.Node("mac", u, v, name="uv")}
    impl.plans = [poly_int.plan_output(coefs, c00, shared, False, env) for c00, coefs in impl.coefs]
    impl.prog = poly_int.build_proven(impl.plans, env, impl.config, ur, (0, 0), impl.describe, WIDTH)


def run_num(impl, clamped: np.ndarray) -> np.ndarray:
    """(N, 2) clamped inputs -> (N, 2) int64 num."""
    u = clamped[:, 0] - impl.maps[0].c
    v = clamped[:, 1] - impl.maps[1].c
    z = np.zeros_like(u)
    return poly_int.evaluate(impl.prog, u, v, z, z, WIDTH)


# ---- C ----------------------------------------------------------------------------------------------

def _operand(b) -> str:
    return b if isinstance(b, str) else i32(b)


def _call(name: str, a: str, b, k: int, f: int) -> str:
    k &= (1 << 64) - 1
    return f"{name}_mac({a}, {_operand(b)}, 0x{k >> 32:08X}UL, 0x{k & 0xFFFFFFFF:08X}UL, {f})"


def lines(impl, indent: str = "    ") -> list[str]:
    """Clamp, inputs, steps, outputs: the body of NAME_ik."""
    p, prog, name = impl.problem, impl.prog, impl.problem.name
    out = []
    for a, src in enumerate("xy"):
        out += [f"if ({src} < {i32(p.lo[a])}) {{ {src} = {i32(p.lo[a])}; clamped = 1; }}",
                f"else if ({src} > {i32(p.hi[a])}) {{ {src} = {i32(p.hi[a])}; clamped = 1; }}"]
    for var, src, m in (("u", "x", impl.maps[0]), ("v", "y", impl.maps[1])):
        out.append(f"{var} = {src} - {i32(m.c)};" if m.c else f"{var} = {src};")
    for st in prog.steps:
        e = _call(name, st.a, st.b, st.K, st.f)
        out.append(f"{st.dst} = {e} + {_operand(st.L)};" if st.L is not None else f"{st.dst} = {e};")
    for k, o in enumerate(prog.outs):
        out.append(f"n = {i32(o.C)};")
        out += [f"n += {_call(name, A, B, 0, t)};" for A, B, t in o.terms]
        out.append(f"n = {i32(o.offset)} + nnik_sar32(n + {i32(1 << (o.s - 1))}, {o.s});")
        if p.code_range is not None:
            lo_, hi_ = (i32(v) for v in p.code_range)
            out += [f"if (n < {lo_}) n = {lo_};", f"else if (n > {hi_}) n = {hi_};"]
        out.append(f"out[{k}] = n;")
    return [indent + s for s in out]


def render(impl) -> str:
    from nnik.implementations.c_common import comment_safe, environment

    p = impl.problem
    outs = [{"label": comment_safe(p.outputs[k]), "shape": plan.shape, "offset": o.offset, "s": o.s,
             "nterms": len(impl.coefs[k][1]) + 1} for k, (plan, o) in enumerate(zip(impl.plans, impl.prog.outs))]
    return environment().get_template("poly32_ik.c.j2").render(
        name=p.name, NAME=p.name.upper(), scenario=comment_safe(p.scn.name), describe=comment_safe(impl.describe()),
        maps=impl.maps, e_in=exponents(impl), symmetry=comment_safe(impl.symmetry_text()), outs=outs,
        symmetry_of="the exact IK" if p.reference is None else "the reference model",
        values=["u", "v"] + [st.dst for st in impl.prog.steps], lines=lines(impl))


def model_bytes(impl) -> int:
    """Constants in the code: int32 multipliers, 64-bit K, int32 L and output constants."""
    prog = impl.prog
    n = sum(4 for st in prog.steps if not isinstance(st.b, str)) + 8 * len(prog.steps)
    n += sum(4 for st in prog.steps if isinstance(st.L, int))
    n += sum(8 + sum(4 for _, b, _ in o.terms if not isinstance(b, str)) for o in prog.outs)
    return n


# ---- cost -------------------------------------------------------------------------------------------

def estimate(impl, target: str) -> dict:
    """Cycles and flash from nnik.implementations.poly.wide_cost's model and its calibration."""
    from nnik.errors import NnikError
    from nnik.implementations.poly import wide_cost

    if not CALIBRATION.exists():
        raise NnikError(f"poly width 32: no calibration ({CALIBRATION.name}); run "
                        "python -m nnik.bench.poly32_calibration")
    cal = json.loads(CALIBRATION.read_text())
    if target not in cal["targets"]:
        raise NnikError(f"unknown target {target!r} (avr | pic18)")
    c = wide_cost.counts(impl, target)
    t = cal["targets"][target]
    ram = 0 if target == "avr" else 40 + 4 * len(impl.prog.steps)
    return {"cycles": wide_cost.predict(t["cycles"], c, wide_cost.FEATURES[target], c["known"]),
            "flash_bytes": int(round(wide_cost.predict(t["flash"], c, wide_cost.FLASH_FEATURES[target]))),
            "ram_bytes": ram, "validated": bool(cal.get("validated")), "cycles_error_pct": stated_band(cal, target)}
