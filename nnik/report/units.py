"""Physical size of one actuator unit (mechanical degrees, belt micrometres)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nnik.report.document import D_DEG, D_UM


@dataclass
class Phys:
    """Physical size of one actuator unit, per output."""

    label: str  # "mech. deg" | "belt µm"
    factors: list[float]
    digits: int
    resolution: str  # human description for the scenario table


def physical_units(scn, n_out: int) -> tuple[Phys | None, str]:
    """(Phys, "") or (None, reason)."""
    if scn is None:
        return None, "scenario unavailable"
    act = scn.actuator
    fam = getattr(scn.mechanism, "family", "")
    unit = act.unit
    if fam == "galvo":
        deg = math.degrees(1.0 / act.units_per_rad)
        return Phys("mech. deg", [deg] * n_out, D_DEG,
                    f"{deg:.6g} mechanical deg per {unit} ({2 * deg:.6g} deg optical)"), ""
    if fam == "belt":
        radii = np.asarray(scn.mechanism.radii, dtype=np.float64)
        um = (radii * 1000.0 / act.units_per_rad).tolist()
        per_rev = act.params["steps_per_rev"] * act.params["microsteps"]
        res = " / ".join(f"{u:.4g}" for u in um)
        return Phys("belt µm", um[:n_out], D_UM,
                    f"{res} µm of belt per {unit} (2πR / {per_rev}, R = "
                    f"{' / '.join(f'{r:.4g}' for r in radii)} mm)"), ""
    if fam == "screw":  # an XY table: table travel per microstep or encoder count
        per_rev = act.units_per_rad * 2 * math.pi
        um = scn.mechanism.params["lead_mm"] * 1000.0 / per_rev
        return Phys("table µm", [um] * n_out, D_UM,
                    f"{um:.4g} µm of table travel per {unit} ({scn.mechanism.params['lead_mm']:g} mm/rev / {per_rev:.6g})"), ""
    if fam == "measured" and act.kind == "stepper" and act.params.get("mm_per_rev"):
        per_rev = act.params["steps_per_rev"] * act.params["microsteps"]
        um = act.params["mm_per_rev"] * 1000.0 / per_rev
        return Phys("belt µm", [um] * n_out, D_UM,
                    f"{um:.4g} µm of belt per {unit} ({act.params['mm_per_rev']:g} mm/rev / {per_rev})"), ""
    return None, f"no physical size known for one {unit} of a {fam or 'this'} machine"
