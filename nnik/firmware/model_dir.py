"""A model directory read once: what a job or an Arduino export needs of OUTDIR, handed down.

`nnik job` and `nnik export --arduino` used to ask OUTDIR again at every step (the trained
scenario, the pick's state, the pick refitted for the IK, again for the library's golden vectors,
again for its label). ModelDir reads each of them once, when first asked; whoever holds the
object never opens the model directory again (the MLP fallback's label, for the library's own
tests only, reads metrics.json when asked).
"""

from __future__ import annotations

from functools import cached_property
from pathlib import Path

from nnik.firmware.ik_oracle import IkFn, ik_of, ik_sources, load_scenario_of, picked_implementation


class ModelDir:
    """OUTDIR as trained and picked: its scenario (model.pt's copy), the pick's integer model
    (None: no finished pick, the MLP stands in) and the bit-exact IK of OUTDIR/c/NAME.c. Each is
    read when first asked (a `nnik job --check` needs no IK) and kept: never twice."""

    def __init__(self, path: Path, status=None):
        """status: OUTDIR's pick_state.status when the caller has it (e.g. from
        pick_state.require_deliverable), so the pick's state is not read twice."""
        self.path = Path(path)
        self._status = status

    @classmethod
    def load(cls, outdir: Path, status=None) -> "ModelDir":
        return cls(outdir, status)

    @cached_property
    def scenario(self):
        """nnik.machine.scenario.Scenario, as trained."""
        return load_scenario_of(self.path)

    @cached_property
    def implementation(self):
        """The pick, refitted (nnik.firmware.ik_oracle.picked_implementation); None: the MLP."""
        return picked_implementation(self.path, self._status)

    @cached_property
    def ik(self) -> IkFn:
        """in_um (N, 2) int64 -> (actuator units (N, 2), clamped flags (N,))."""
        return ik_of(self.path, self.implementation)

    @property
    def name(self) -> str:
        return self.scenario.name

    def c_sources(self) -> Path:
        """The directory of the NAME.c/NAME.h that ik answers for (NnikError: none there)."""
        return ik_sources(self.path, self.name, self.implementation is not None)

    def label(self) -> tuple[str, str]:
        """(what the IK is, its hash) for the library's header: the pick's, else the MLP's shape."""
        if self.implementation is not None:
            return self.implementation.describe(), self.implementation.source_hash()
        from nnik import pipeline

        metrics = pipeline.load_metrics(self.path)
        return ("MLP " + "-".join(map(str, metrics.get("network", {}).get("shape", []))),
                metrics.get("fixed", {}).get("model_hash", "-"))
