"""Pretraining both neural controllers for `nnik run` on a DC-servo xy_table: the seed's tests as
the shipped jobs give them (datasets/jobs/servo_step_x25.gcode, servo_step_y20.gcode and the
reference job, through the same planner as every closed-loop job) on the identified models
(nnik.implementations.servo.nn.pretrain, which defines the episodes and the 2 % stop rule).
"""

from __future__ import annotations

from pathlib import Path

from nnik.implementations.servo import NEURAL
from nnik.implementations.servo.nn.pretrain import EPISODES, pretrain

JOBS = Path(__file__).resolve().parents[2] / "datasets" / "jobs"
PRETRAIN_JOBS = ("servo_step_x25.gcode", "servo_step_y20.gcode", "xy_table_reference.gcode")


def pretrain_tests(scn) -> list[tuple[str, object]]:
    """[(job name, reference counts (N, 2))] of the seed's tests for the scenario."""
    from nnik.job.parse import JobRequest
    from nnik.job.reference import job_reference

    return [(job, job_reference(JobRequest(JOBS / job, scn))[1].counts) for job in PRETRAIN_JOBS]


def pretrain_all(scn, models, coulomb_v, seed: int, episodes: int = EPISODES, say=print,
                 kinds=NEURAL) -> tuple[dict, dict]:
    """({kind: params}, {kind: log}) for each neural kind, and one line each said."""
    tests = pretrain_tests(scn)
    params, logs = {}, {}
    for kind in kinds:
        params[kind], logs[kind] = pretrain(kind, scn.servo, models, coulomb_v, seed, episodes, tests)
        say(summary(logs[kind]))
    return params, logs


def summary(log: dict) -> str:
    """One line: how many episodes, the chosen grid point, each test's worst error against its 2 %."""
    worst = {n: f"{max(f['steady_state_um'], f['overshoot_um']):.0f}/{f['allowed_um']:.0f}"
             for n, f in log["verify"].items()}
    return (f"pretrained {log['kind']} on the identified model: "
            + (f"below 2 % after {log['episodes']} episode(s)" if log["passed"] else
               f"NOT below 2 % within {log['episodes']} episodes")
            + f" (eta_shift {log['eta_shift']}, in_shift {log['in_shift']}; the pretrained weights from power-on, "
            + "worst of steady-state error and overshoot / 2 % of the reference, um: "
            + ", ".join(f"{n} {w}" for n, w in worst.items()) + ")")
