"""The speed reference a skeptic asks for, with the families' C API: the float IK in C99.

It emits ``int8_t NAME_float_ik(const int32_t in_um[2], int32_t out[2])`` with the families'
contract: inputs are the target position in integer micrometres, clamped to the domain exactly
as :func:`nnik.machine.domain.clamp_um` does (the return value is 1 if an input was clamped, else
0); outputs are whole actuator units (microsteps or DAC LSB, counted from rest) rounded to
nearest, and for a DAC clamped to its code range.

Float (:func:`render_float_c`)
    C99 ``float`` + ``math.h``: the exact analytic IK of the mechanism with its parameters baked
    in. Galvos use ``atan2f``/``sqrtf``; belt machines without nonlinear distortion are affine
    (the inverse of the 2x2 frame map is precomputed). Belt machines with nonlinear distortion
    and measured machines have no closed form, see :func:`float_unavailable_reason`.
    :func:`float_ik_reference` mirrors the C in numpy float32 (close, not bit exact: libm
    differs between platforms).
"""

from __future__ import annotations

import numpy as np

from nnik.machine.domain import clamp_um, domain_um
from nnik.emit.c_text import c_comment_safe
from nnik.errors import NnikError
from nnik.emit.templating import CODEGEN, RUNTIME, environment
from nnik.machine.scenario import Scenario

RUNTIME_DIR = RUNTIME
HOST_DRIVER = CODEGEN / "harness" / "host" / "ik_driver.c"

NO_CLOSED_FORM = (
    "no closed-form inverse with nonlinear distortion; Newton in float on an 8-bit MCU is not "
    "a fair baseline"
)
NO_MODEL = "a measured machine has no model, so there is no closed-form IK to evaluate in float"


def _check_name(name: str) -> str:
    if not name.isidentifier() or not name.isascii():
        raise NnikError(f"C prefix {name!r} is not an identifier")
    return name


def _i32(v: int) -> str:
    """An int32 constant as C that is correct on 16-bit-int targets too."""
    v = int(v)
    if not -(2**31) < v < 2**31:
        raise NnikError(f"constant {v} does not fit int32")
    return f"((int32_t){v}L)"


def _cf(v: float) -> str:
    """A float constant as a C float literal (9 significant digits round-trip a float32)."""
    s = f"{float(np.float32(v)):.9g}"
    if not any(c in s for c in ".en"):
        s += ".0"
    return s + "f"


def _domain_ctx(scn: Scenario) -> dict:
    lo, hi = domain_um(scn.workspace)
    return {"lo": [_i32(v) for v in lo], "hi": [_i32(v) for v in hi],
            "lo_um": [int(v) for v in lo], "hi_um": [int(v) for v in hi]}


def float_unavailable_reason(scn: Scenario) -> str | None:
    """Why the scenario has no float baseline, or None if it has one."""
    m = scn.mechanism
    if not m.analytic:
        return NO_MODEL
    if m.family == "belt" and m.nonlinear:
        return NO_CLOSED_FORM
    if m.kind not in ("galvo_gimbal", "galvo_dual") and m.family != "belt":
        return f"no float baseline for mechanism kind {m.kind!r}"
    return None


def _belt_affine(scn: Scenario) -> dict:
    """Belt machine without nonlinear terms: (u, v) = Finv p, then out_i = KU_i u + KV_i v + K0_i
    (units). The belt layout `from_uv` is affine; its coefficients are read off it."""
    m = scn.mechanism
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    b = m.from_uv(uv)  # belt mm
    c0, cu, cv = b[0], b[1] - b[0], b[2] - b[0]
    probe = np.array([[0.37, -1.9], [250.0, 13.0]])
    if not np.allclose(m.from_uv(probe), c0 + probe[:, :1] * cu + probe[:, 1:] * cv, atol=1e-9):
        raise NnikError(f"{m.kind}: belt layout is not affine; no float baseline")
    scale = scn.actuator.units_per_rad / m.radii  # units per belt mm
    return {"finv": m.frame_inv, "ku": cu * scale, "kv": cv * scale, "k0": c0 * scale}


def _float_consts(scn: Scenario) -> dict:
    m = scn.mechanism
    upr = scn.actuator.units_per_rad
    if m.kind == "galvo_gimbal":
        z = m.params["z_mm"]
        return {"Z": z, "ZZ": z * z, "K": 0.5 * upr}
    if m.kind == "galvo_dual":
        d = m.params["d_mm"]
        return {"D": d, "DD": d * d, "E": m.params["e_mm"], "K": 0.5 * upr}
    return _belt_affine(scn)


def float_ik_reference(scn: Scenario, in_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The float C's computation in numpy float32 -> (out int64 (N, 2), flags int64 (N,)).

    Close to the C (same operations, same float32 constants) but not bit exact: atan2f and
    sqrtf differ between libms by an ulp or so, which can move a result across a rounding
    boundary.
    """
    reason = float_unavailable_reason(scn)
    if reason:
        raise NnikError(reason, scn.source, "[mechanism]")
    f32 = np.float32
    c, flags = clamp_um(np.asarray(in_um).reshape(-1, 2), scn.workspace)
    x = c[:, 0].astype(f32) * f32(0.001)
    y = c[:, 1].astype(f32) * f32(0.001)
    k = _float_consts(scn)
    kind = scn.mechanism.kind
    if kind == "galvo_gimbal":
        q0 = np.arctan2(y, f32(k["Z"])) * f32(k["K"])
        q1 = -np.arctan2(x, np.sqrt(y * y + f32(k["ZZ"]))) * f32(k["K"])
    elif kind == "galvo_dual":
        q0 = np.arctan2(x, np.sqrt(f32(k["DD"]) + y * y) + f32(k["E"])) * f32(k["K"])
        q1 = np.arctan2(y, f32(k["D"])) * f32(k["K"])
    else:
        fi = k["finv"].astype(f32)
        u = fi[0, 0] * x + fi[0, 1] * y
        v = fi[1, 0] * x + fi[1, 1] * y
        ku, kv, k0 = (k[n].astype(f32) for n in ("ku", "kv", "k0"))
        q0 = ku[0] * u + kv[0] * v + k0[0]
        q1 = ku[1] * u + kv[1] * v + k0[1]
    out = np.stack([_round_f32(q0), _round_f32(q1)], 1)
    if scn.actuator.code_range is not None:
        out = np.clip(out, *scn.actuator.code_range)
    return out, flags


def _round_f32(v: np.ndarray) -> np.ndarray:
    """C: v >= 0 ? (int32_t)(v + 0.5f) : -(int32_t)(0.5f - v)."""
    v = v.astype(np.float32)
    half = np.float32(0.5)
    pos = np.trunc(v + half)
    neg = -np.trunc(half - v)
    return np.where(v >= 0, pos, neg).astype(np.int64)


def render_float_c(scn: Scenario, name: str | None = None) -> dict[str, str] | None:
    """C99 float sources {"NAME_float.h": ..., "NAME_float.c": ...}, or None (see
    :func:`float_unavailable_reason`). Link with -lm on a hosted compiler."""
    if float_unavailable_reason(scn):
        return None
    name = _check_name(name or scn.name)
    m = scn.mechanism
    k = _float_consts(scn)
    consts = {}
    if m.kind in ("galvo_gimbal", "galvo_dual"):
        consts = {n: _cf(v) for n, v in k.items()}
    else:
        for i in range(2):
            for j in range(2):
                consts[f"FI{i}{j}"] = _cf(k["finv"][i, j])
            consts[f"KU{i}"] = _cf(k["ku"][i])
            consts[f"KV{i}"] = _cf(k["kv"][i])
            consts[f"K0{i}"] = _cf(k["k0"][i])
    ctx = dict(
        prefix=f"{name}_float",
        guard=f"NNIK_{name.upper()}_FLOAT_H",
        scn=scn,
        scenario_text=c_comment_safe(scn.name),
        kind=m.kind,
        family=m.family,
        mech=c_comment_safe(m.describe()),
        actuator=c_comment_safe(scn.actuator.describe()),
        unit=scn.unit,
        outputs=scn.outputs,
        c=consts,
        code_range=scn.actuator.code_range,
        dist=getattr(m, "dist", None),
        **_domain_ctx(scn),
    )
    env = environment()
    return {
        f"{name}_float.h": env.get_template("float_ik.h.j2").render(**ctx),
        f"{name}_float.c": env.get_template("float_ik.c.j2").render(**ctx),
    }
