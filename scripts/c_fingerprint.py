"""Fingerprint of the C nnik emits: the hash of every family's reference configurations (the keys
its calibration is stored under), plus each shipped scenario's first ladder rung of every table
and polynomial family, rendered.  Run before and after a refactor that must not change the C:

    python3 scripts/c_fingerprint.py > before.json   # ... move things ...
    python3 scripts/c_fingerprint.py | diff before.json -

It also says whether each recomputed key still equals the key stored in nnik/calibration/*.json
("stored_ok"): a move that keeps the C keeps the calibrations valid.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _attr(candidates: list[str], name: str):
    """`name` from the first module of `candidates` that imports (the layout before and after)."""
    for mod in candidates:
        try:
            return getattr(importlib.import_module(mod), name)
        except ModuleNotFoundError:
            continue
    raise ImportError(f"{name} not found in {candidates}")


def main() -> dict:
    from nnik.implementations import family

    cal = ROOT / "nnik" / "calibration"
    out: dict = {}
    # the MLP: the estimator's reference models per kernel
    reference_c_hash = _attr(["nnik.implementations.mlp.cost.validity", "nnik.estimate.validity"], "reference_c_hash")
    stored_hash = _attr(["nnik.implementations.mlp.cost.validity", "nnik.estimate.validity"], "stored_hash")
    for prof in ("avr-gcc-Os", "avr-gcc-O2", "pic18-sdcc"):
        data = json.loads((cal / f"{prof}.json").read_text())
        for kkey, kc in sorted(data.get("kernels", {}).items()):
            h = reference_c_hash(kc.get("kernel"))
            out[f"mlp:{prof}:{kkey}"] = {"hash": h, "stored_ok": h == stored_hash(data, kkey)}
    # poly
    reference_key = _attr(["nnik.implementations.poly.cost", "nnik.implementations.poly_cost"], "reference_key")
    h = reference_key(family("poly"))
    out["poly"] = {"hash": h, "stored_ok": h == json.loads((cal / "poly.json").read_text()).get("key")}
    # lut and hybrid
    reference_hash = _attr(["nnik.implementations.lut.reference", "nnik.implementations.lut_reference"],
                           "reference_hash")
    for fam in ("lut", "hybrid"):
        h = reference_hash(family(fam))
        out[fam] = {"hash": h, "stored_ok": h == json.loads((cal / f"{fam}.json").read_text()).get("key")}
    # every shipped scenario: the first rung of each non-MLP family's ladder, rendered
    from nnik.implementations.problem import Problem
    build_dataset = _attr(["nnik.machine.data", "nnik.data"], "build_dataset")
    load_scenario = _attr(["nnik.machine.scenario", "nnik.scenario"], "load_scenario")
    for toml in sorted((ROOT / "datasets").glob("*.toml")):
        try:
            scn = load_scenario(toml)
            prob = Problem(scn, build_dataset(scn), unit_um=scn.export.get("input_unit_um", 1.0))
        except Exception as exc:  # measured machines need their marks; say so, do not fail
            out[f"scenario:{toml.stem}"] = f"skipped: {type(exc).__name__}"
            continue
        for fam in ("poly", "lut", "hybrid"):
            cls = family(fam)
            try:
                src = cls.fit(prob, cls.ladder(prob)[0]).render_source()
                out[f"scenario:{toml.stem}:{fam}"] = hashlib.sha256(src.encode()).hexdigest()[:16]
            except Exception as exc:
                out[f"scenario:{toml.stem}:{fam}"] = f"error: {type(exc).__name__}: {exc}"[:120]
    return out


if __name__ == "__main__":
    print(json.dumps(main(), indent=1, sort_keys=True))
