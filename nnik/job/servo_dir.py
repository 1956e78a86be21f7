"""A DC-servo xy_table's output directory (what `nnik run datasets/xy_table.toml` writes and `nnik
job OUTDIR JOB.gcode` reads), read once:

    OUTDIR/scenario.toml            the scenario as run (its [servo] is the true plant)
    OUTDIR/servo/identified.toml    the identified speed models, as scenario lines
    OUTDIR/servo/gains.json         {"chosen": KIND, "gains": {KIND: {...}}, "objective": ...}: a
                                    baseline's gains, a neural controller's params (its pretrained
                                    integer weights and formats, nnik.implementations.servo.nn)
    OUTDIR/c/                       the chosen controller's C and nnik_servo_config.h
    OUTDIR/report/closed_loop.md    the seed's tests per controller, and their PNGs
    OUTDIR/job/JOB.json, JOB.png    each closed-loop job
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from nnik.errors import NnikError
from nnik.implementations.servo import KINDS  # noqa: F401 (the baselines, then the learning controllers)

SCENARIO_FILE = "scenario.toml"
SERVO_DIR = "servo"
GAINS_FILE = "servo/gains.json"
IDENTIFIED_FILE = "servo/identified.toml"


def is_servo_dir(path: Path) -> bool:
    return (Path(path) / GAINS_FILE).is_file()


@dataclass(frozen=True)
class ServoDir:
    path: Path
    scenario: object  # nnik.machine.scenario.Scenario, a dc_servo xy_table
    chosen: str
    gains: dict  # kind -> that controller's gains

    @classmethod
    def load(cls, path: Path, scenario=None) -> "ServoDir":
        """scenario: the TOML's (given on the command line) instead of OUTDIR's copy."""
        from nnik.machine.scenario import load_scenario

        path = Path(path)
        if not is_servo_dir(path):
            raise NnikError("no tuned controllers here (run `nnik run SCENARIO -o DIR` on a dc_servo xy_table first)",
                            str(path))
        try:
            data = json.loads((path / GAINS_FILE).read_text())
            chosen, gains = data["chosen"], data["gains"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise NnikError(f"unreadable: {exc}", str(path / GAINS_FILE)) from None
        scn = scenario if scenario is not None else load_scenario(path / SCENARIO_FILE)
        if scn.servo is None:
            raise NnikError("not a dc_servo xy_table scenario", scn.source)
        return cls(path, scn, chosen, gains)

    def controller(self, kind: str | None):
        """The tuned controller of that kind (None: the chosen one): its integer Python model."""
        from nnik.implementations.servo import make

        kind = kind or self.chosen
        if kind not in self.gains:
            raise NnikError(f"no tuned {kind!r} controller in {self.path / GAINS_FILE} (it has "
                            f"{', '.join(sorted(self.gains))})", None, "--controller")
        return make(kind, self.gains[kind], self.scenario.servo)
