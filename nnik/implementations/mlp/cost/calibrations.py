"""Compiler profiles and their calibration files (package data under nnik/calibration/)."""

from __future__ import annotations

import functools
import json
from pathlib import Path

from nnik.errors import NnikError

PACKAGE_DIR = Path(__file__).resolve().parents[3]  # nnik/ (this file: nnik/implementations/mlp/cost/)
CAL_DIR = PACKAGE_DIR / "calibration"
REPO_ROOT = PACKAGE_DIR.parent
CALIBRATION_FORMAT = 1

TARGETS = ("avr", "pic18")
# clock periods per counted cycle: simavr counts CPU cycles, gpsim instruction cycles (Fosc/4)
CLOCKS_PER_CYCLE = {"avr": 1, "pic18": 4}
BUILTIN_PROFILES = {
    "avr-gcc-Os": {"target": "avr", "compiler": "avr-gcc", "opt": "-Os",
                   "description": "ATmega328P, avr-gcc -Os (simavr)"},
    "avr-gcc-O2": {"target": "avr", "compiler": "avr-gcc", "opt": "-O2",
                   "description": "ATmega328P, avr-gcc -O2 (simavr)"},
    "pic18-sdcc": {"target": "pic18", "compiler": "sdcc", "opt": "",
                   "description": "PIC18F452, SDCC pic16 (gpsim, instruction cycles = Fosc/4)"},
}
DEFAULT_PROFILE = {"avr": "avr-gcc-Os", "pic18": "pic18-sdcc"}
DEFAULT_KERNEL_KEY = "default"

# the goals a recorded validation sweep must meet for its estimates to count as validated
GOAL_CYCLES_PCT = 3.0
GOAL_FLASH_PCT = 5.0


def cal_path(profile: str) -> Path:
    return CAL_DIR / f"{profile}.json"


@functools.cache
def _load_cal_cached(path: str, mtime: float) -> dict:
    return json.loads(Path(path).read_text())


def load_calibration(profile: str) -> dict:
    """The calibration data of a profile (raises NnikError if it is missing)."""
    path = cal_path(profile)
    if not path.is_file():
        raise NnikError(f"no calibration for profile {profile!r} (run `python3 -m nnik.bench.mlp_cost calibrate "
                        f"--target {_profile_target(profile)}`)", str(path))
    try:
        data = _load_cal_cached(str(path), path.stat().st_mtime)
    except json.JSONDecodeError as exc:
        raise NnikError(f"corrupt calibration file ({exc})", str(path)) from None
    if data.get("format") != CALIBRATION_FORMAT:
        raise NnikError(f"calibration format {data.get('format')!r}, expected {CALIBRATION_FORMAT} (re-run calibrate)",
                        str(path))
    return data


def _profile_target(profile: str) -> str:
    if profile in BUILTIN_PROFILES:
        return BUILTIN_PROFILES[profile]["target"]
    return profile.split("-", 1)[0]


def profiles(target: str | None = None) -> list[str]:
    """Profile names: the built-in simulator-calibrated ones plus any extra calibration files
    (e.g. an extrapolated, unvalidated compiler profile); optionally only those of a target."""
    names = list(BUILTIN_PROFILES)
    if CAL_DIR.is_dir():
        for p in sorted(CAL_DIR.glob("*.json")):
            if p.stem not in names:
                names.append(p.stem)
    if target is not None:
        names = [n for n in names if _profile_target(n) == target]
    return names


def resolve_profile(target: str, profile: str | None = None) -> str:
    """Full profile name from a target and an optional profile or compiler spelling:
    None (the target's default), a full name ("avr-gcc-O2"), or a short one ("O2", "-O2", "sdcc")."""
    if target not in TARGETS:
        raise NnikError(f"unknown target {target!r}; known targets: {', '.join(TARGETS)}")
    if profile is None or profile == "":
        return DEFAULT_PROFILE[target]
    names = profiles(target)
    if profile in names:
        return profile
    key = profile.lstrip("-").lower()
    matches = [n for n in names if n.lower().endswith(key) or n.lower().split("-", 1)[-1] == key
               or key in n.lower().split("-")]
    if len(matches) == 1:
        return matches[0]
    other = [n for n in profiles() if n not in names and (n == profile or n.lower().endswith(key))]
    hint = f" ({profile!r} is a profile of target {_profile_target(other[0])!r})" if other else ""
    raise NnikError(f"unknown profile {profile!r} for target {target!r}{hint}; known: {', '.join(names)}")


def forget_loaded() -> None:
    """Drop the cached calibration files (after writing one)."""
    _load_cal_cached.cache_clear()
