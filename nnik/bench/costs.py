"""The families' cost models (poly, poly width 32, lut, hybrid) against simavr and gpsim.

Configurations are drawn the way `nnik search` draws them (nnik.search.space.suggest, the family
fixed, every knob from a seeded RNG), on every shipped scenario and on random machines; each is
fitted, its estimate() taken, and its C measured on the simulators (mean cycles over in-domain
vectors).  ``--record`` stores each family's measured band per target (the worst |error| of the
run plus a margin, rounded up to 0.1 %) in its calibration file, where estimate() reads the band it states.

    python3 -m nnik.bench.costs [--targets avr,pic18] [--per-scenario 3] [--machines 4] [--record]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from nnik.implementations.lut.cost import CALIBRATION as CAL_DIR
from nnik.implementations.lut.cost import load as load_lut_cal
from nnik.implementations.poly.wide import CALIBRATION as POLY32_CAL

DATASETS = Path(__file__).resolve().parents[2] / "datasets"
SCENARIOS = ("galvo_cba2012", "galvo_dual_xy2", "corexy_nonlinear", "hbot_unicamp", "corexy_measured")
# a family and its calibration file ("poly32" is poly's wide path)
KINDS = {"poly": "poly", "poly32": "poly32", "lut": "lut", "hybrid": "hybrid"}
BAND_GOAL_PCT = 3.0


class RandomTrial:
    """An optuna-like trial whose every suggestion is a seeded random draw."""

    def __init__(self, rng: np.random.Generator, fixed: dict):
        self.rng, self.fixed, self.params = rng, fixed, {}

    def _keep(self, name, v):
        v = self.fixed.get(name, v)
        self.params[name] = v
        return v

    def suggest_categorical(self, name, choices):
        return self._keep(name, choices[int(self.rng.integers(0, len(choices)))])

    def suggest_int(self, name, lo, hi):
        return self._keep(name, int(self.rng.integers(lo, hi + 1)))


def draw_config(problem, kind: str, rng: np.random.Generator) -> tuple[str, dict]:
    """(family, config) as `nnik search` would propose for this kind."""
    from nnik.search.space import suggest

    fam = "poly" if kind.startswith("poly") else kind
    fixed = {"family": fam}
    if fam == "poly":
        fixed["poly_width"] = 32 if kind == "poly32" else 16
    return suggest(RandomTrial(rng, fixed), problem, [fam])


def problem_of(path: Path):
    from nnik.implementations.problem import Problem
    from nnik.machine.data import build_dataset
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(path)
    return Problem(scn, build_dataset(scn), unit_um=scn.export["input_unit_um"])


def fit(problem, fam: str, config: dict):
    from nnik.implementations import family

    return family(fam).fit(problem, config)


def measure(impl, targets, workdir: Path, n_inside: int = 40) -> list[dict]:
    """Predicted vs measured cycles of one fitted configuration on each target."""
    from nnik.implementations.verify import verify_on_target

    rows = []
    for t in targets:
        est = impl.estimate(t)
        r = verify_on_target(impl, t, workdir / "c", workdir / t, n_inside=n_inside)
        if "not_run" in r:
            continue
        meas = float(r["cycles"])
        rows.append({"target": t, "cycles_pred": round(float(est["cycles"]), 1), "cycles_meas": round(meas, 1),
                     "err_pct": round(100 * (float(est["cycles"]) - meas) / meas, 2),
                     "validated": bool(est.get("validated")), "stated_pct": est.get("cycles_error_pct"),
                     "bit_exact": bool(r["bit_exact"])})
    return rows


def kind_of(impl) -> str:
    return "poly32" if impl.family == "poly" and impl.config.get("width", 16) == 32 else impl.family


def check(problems: dict, kinds, targets, per_problem: int, seed: int, workdir: Path, say=print) -> list[dict]:
    """Draw `per_problem` configurations of each kind on each problem and measure them."""
    rows = []
    for pi, (label, problem) in enumerate(problems.items()):
        for ki, kind in enumerate(kinds):
            rng = np.random.default_rng([seed, pi, ki])
            for n in range(per_problem):
                fam, cfg = draw_config(problem, kind, rng)
                try:
                    impl = fit(problem, fam, cfg)
                except Exception as exc:  # noqa: BLE001 - a draw the family refuses (the search skips it too)
                    say(f"  {label} {kind} {cfg}: not fitted ({type(exc).__name__}: {exc})")
                    continue
                for r in measure(impl, targets, workdir / f"{label}-{kind}-{n}"):
                    r.update({"scenario": label, "kind": kind_of(impl), "config": cfg})
                    rows.append(r)
                    say(f"  {label:18s} {r['kind']:7s} {r['target']:5s} {r['cycles_pred']:9.0f} vs "
                        f"{r['cycles_meas']:9.0f}  {r['err_pct']:+6.2f} %  (states ±{r['stated_pct']})")
    return rows


def summary(rows: list[dict]) -> dict:
    """{kind: {target: {cases, min_pct, max_pct, max_abs_pct}}}."""
    out: dict = {}
    for r in rows:
        s = out.setdefault(r["kind"], {}).setdefault(r["target"], {"cases": 0, "min_pct": math.inf,
                                                                    "max_pct": -math.inf})
        s["cases"] += 1
        s["min_pct"] = min(s["min_pct"], r["err_pct"])
        s["max_pct"] = max(s["max_pct"], r["err_pct"])
    for k in out.values():
        for s in k.values():
            s["max_abs_pct"] = max(abs(s["min_pct"]), abs(s["max_pct"]))
    return out


MARGIN_PCT = 0.5  # added to the worst error seen, for the configurations no check has drawn


def band_of(max_abs_pct: float) -> float:
    """The band a run supports: its worst |error| plus MARGIN_PCT, rounded up to 0.1 %."""
    return math.ceil(10 * (max_abs_pct + MARGIN_PCT) - 1e-9) / 10


def _cal_path(kind: str) -> Path:
    return POLY32_CAL if kind == "poly32" else CAL_DIR / f"{kind}.json"


def record(summ: dict, how: str) -> None:
    """Store each kind's measured band per target in its calibration file ("check"), replacing
    the targets this run measured."""
    for kind, per_t in summ.items():
        path = _cal_path(kind)
        cal = json.loads(path.read_text())
        chk = cal.get("check") or {"targets": {}}
        for t, s in per_t.items():  # a run on some targets keeps the others' recorded bands
            chk["targets"][t] = {**s, "band_pct": band_of(s["max_abs_pct"]), "how": how}
        cal["check"] = {"targets": chk["targets"]}
        path.write_text(json.dumps(cal, indent=1) + "\n")
    load_lut_cal.cache_clear()


def stated_band(kind: str, target: str) -> float | None:
    """The cycle band a family's cost model states on a target (from its recorded check)."""
    path = _cal_path(kind)
    if not path.exists():
        return None
    t = (json.loads(path.read_text()).get("check") or {}).get("targets", {}).get(target)
    return None if t is None else float(t["band_pct"])


def random_machine(rng: np.random.Generator) -> str:
    """A scenario nobody shipped: a galvo (gimbal or two mirrors, stepper or DAC) or a belt frame."""
    from nnik.bench.measured import BELT_DISTORTION, BELT_SPANS, belt_toml

    if rng.random() < 0.4:
        dist = {k: float(rng.uniform(lo, hi)) for k, (lo, hi) in BELT_DISTORTION.items()}
        return belt_toml("rnd", str(rng.choice(["corexy", "hbot"])), BELT_SPANS[int(rng.integers(0, len(BELT_SPANS)))],
                         dist)
    z = float(rng.uniform(120.0, 400.0))
    half = float(rng.uniform(0.15, 0.35)) * z
    cx, cy = (float(rng.uniform(-0.4, 0.4)) * half for _ in range(2))
    asp = float(rng.uniform(0.5, 1.0))
    mech = (f'kind = "galvo_gimbal"\nz_mm = {z:.1f}' if rng.random() < 0.5
            else f'kind = "galvo_dual"\nd_mm = {z:.1f}\ne_mm = {float(rng.uniform(5.0, 20.0)):.1f}')
    act = str(rng.choice(["stepper", "dac12", "dac16"]))
    actuator = ('kind = "stepper"\nsteps_per_rev = 200\nmicrosteps = 16' if act == "stepper" else
                f'kind = "dac"\nbits = {12 if act == "dac12" else 16}\noptical_range_deg = 60.0')
    unit = "[export]\ninput_unit_um = 0.25\n" if act == "dac16" else ""
    return (f'name = "rnd"\n[mechanism]\n{mech}\n[actuator]\n{actuator}\n[workspace]\n'
            f'x_mm = [{cx - half:.1f}, {cx + half:.1f}]\ny_mm = [{cy - half * asp:.1f}, {cy + half * asp:.1f}]\n{unit}')


def random_problems(n: int, seed: int, workdir: Path) -> dict:
    rng = np.random.default_rng(seed)
    out = {}
    for i in range(n):
        path = workdir / f"machine{i}.toml"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(random_machine(rng))
        out[f"machine{i}"] = problem_of(path)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m nnik.bench.costs", description=__doc__.split("\n\n")[0])
    ap.add_argument("--targets", default="avr,pic18")
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--per-scenario", type=int, default=3)
    ap.add_argument("--machines", type=int, default=4)
    ap.add_argument("--seed", type=int, default=2511)
    ap.add_argument("--record", action="store_true")
    ap.add_argument("--json", type=Path, help="write every row here")
    a = ap.parse_args(argv)
    targets, kinds = a.targets.split(","), a.kinds.split(",")
    with tempfile.TemporaryDirectory(prefix="nnik-costs-") as tmp:
        work = Path(tmp)
        problems = {s: problem_of(DATASETS / f"{s}.toml") for s in SCENARIOS}
        problems.update(random_problems(a.machines, a.seed, work / "machines"))
        rows = check(problems, kinds, targets, a.per_scenario, a.seed, work)
    summ = summary(rows)
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1) + "\n")
    for kind, per_t in summ.items():
        for t, s in per_t.items():
            print(f"{kind:7s} {t:5s} {s['cases']:3d} cases  error {s['min_pct']:+.2f} .. {s['max_pct']:+.2f} %")
    if a.record:
        record(summ, f"python3 -m nnik.bench.costs --kinds {a.kinds} --per-scenario {a.per_scenario} "
                     f"--machines {a.machines} --seed {a.seed} --targets {a.targets}")
    worst = max((s["max_abs_pct"] for k in summ.values() for s in k.values()), default=0.0)
    return 0 if worst <= BAND_GOAL_PCT else 1


if __name__ == "__main__":
    sys.exit(main())
