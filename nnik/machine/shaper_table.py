"""The scenario's [shaper] table: the input shaper per axis as Klipper's [input_shaper] section
takes it (the same keys and defaults).

[shaper]  shaper_type                both axes' type (default mzv, as Klipper's)
          shaper_type_x, shaper_type_y   an axis's own type: zv, mzv, zvd, ei, 2hump_ei, 3hump_ei
                                     (any case), or none
          shaper_freq_x, shaper_freq_y   the axis's shaper frequency, Hz; 0 or left out: that axis
                                     is not shaped (Klipper's default)
          damping_ratio_x, damping_ratio_y   the damping ratio the shaper is designed for
                                     (default 0.1); at most Klipper's limit for the type: 0.99
                                     (zv, mzv, zvd), 0.4 (ei), 0.3 (2hump_ei), 0.2 (3hump_ei)

The older form, [motion] shaper = KIND with the [dynamics] resonance, keeps working: it designs
KIND for [dynamics] f_hz and zeta on each axis.  A scenario gives one form or the other ([motion]
shaper = "none" beside a [shaper] table is no conflict).
"""

from __future__ import annotations

from nnik.dynamics.shapers import KINDS, MAX_ZETA
from nnik.errors import NnikError
from nnik.machine.params import Param, validate_table, within

DEFAULT_TYPE = "mzv"
DEFAULT_ZETA = 0.1


def _type(v):
    return None if v.lower() in KINDS + ("none",) else f"must be one of none, {', '.join(KINDS)}, got {v!r}"


SHAPER = {
    "shaper_type": Param("str", default=DEFAULT_TYPE, check=_type),
    **{f"shaper_type_{a}": Param("str", check=_type) for a in "xy"},
    **{f"shaper_freq_{a}": Param("float", default=0.0, check=within(0.0, 1e4, unit=" Hz")) for a in "xy"},
    **{f"damping_ratio_{a}": Param("float", default=DEFAULT_ZETA, check=within(0.0, 0.99)) for a in "xy"},
}


def label(types: tuple[str, str]) -> str:
    """The machine's shaper name for per-axis types: 'x/y', e.g. 'mzv/ei' (both listed, even
    when equal, so a [shaper] table is never mistaken for [motion] shaper's single kind)."""
    return "/".join(types)


def validate_shaper(raw, motion: dict, motion_raw, source: str) -> dict | None:
    """[shaper] as {"type": (tx, ty), "freq_hz": (fx, fy), "damping": (zx, zy), "label": "tx/ty"}
    (an axis without a frequency: type none; neither axis shaped: label "none"), or None
    without the table.  With the table, motion["shaper"] becomes its label."""
    if raw is None or raw == {}:
        return None
    if isinstance(motion_raw, dict) and motion_raw.get("shaper", "none") != "none":
        raise NnikError("give the shaper in [shaper] (Klipper's keys) or in [motion] shaper, not both",
                        source, "[motion] shaper")
    t = validate_table(raw, SHAPER, source, "shaper")
    types, freqs, zetas = [], [], []
    for a in "xy":
        kind = (t[f"shaper_type_{a}"] or t["shaper_type"]).lower()
        f, z = t[f"shaper_freq_{a}"], t[f"damping_ratio_{a}"]
        if kind != "none" and z > MAX_ZETA[kind]:
            raise NnikError(f"{kind} holds to a damping ratio of {MAX_ZETA[kind]:g} (Klipper's limit), got {z:g}",
                            source, f"[shaper] damping_ratio_{a}")
        hi = motion["sample_hz"] / 4
        if kind != "none" and f and not 1.0 <= f < hi:
            raise NnikError(f"must be in [1, {hi:g}) Hz, a quarter of the {motion['sample_hz']} Hz sample rate "
                            f"(so the shaper's taps resolve the period), or 0 for no shaping, got {f:g}",
                            source, f"[shaper] shaper_freq_{a}")
        if not f:
            kind = "none"
        types.append(kind)
        freqs.append(f)
        zetas.append(z)
    name = "none" if types == ["none", "none"] else label(tuple(types))
    out = {"type": tuple(types), "freq_hz": tuple(freqs), "damping": tuple(zetas), "label": name}
    motion["shaper"] = out["label"]
    return out
