"""Pick what to flash: fit every implementation family over its ladder, keep the configurations
that meet ``[target] max_error`` on the dense check grid, verify each family's best on the host
and on both simulated chips, and pick the cheapest by measured cycles on ``[target] chip`` (flash
breaks ties) within the optional ``max_cycles`` / ``max_flash_bytes`` limits.

Layout written under OUTDIR/c/: ``NAME.c``/``NAME.h`` is the pick; ``alt/<family>/NAME.{c,h}`` is
each family's best (the pick's family included), all with the same API ``NAME_ik``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from nnik.files.c_hash import files_hash
from nnik.errors import NnikError
from nnik.implementations import FAMILIES, Implementation, Problem
from nnik.implementations.accuracy import accuracy
from nnik.implementations.base import TARGETS
from nnik.implementations.lut.family import CHIP_FLASH
from nnik.implementations.verify import verify_host, verify_on_target

ALT_DIR = "alt"


@dataclass
class Candidate:
    family: str
    config: dict
    impl: Implementation | None = None
    acc: dict = field(default_factory=dict)
    est: dict = field(default_factory=dict)  # target -> estimate
    skipped: str | None = None
    checks: dict = field(default_factory=dict)  # "host"/"avr"/"pic18" -> verification result

    @property
    def claimed_max(self) -> float:
        """The accuracy claimed and judged against max_error: pre_max for an exact IK; for a
        measured machine, the error against the machine its reference's bootstrap supports
        (accuracy()'s ``claimed_max``: the implementation's error field plus the reference's)."""
        if "claimed_max" in self.acc:
            return self.acc["claimed_max"]
        return self.acc.get("pre_max", float("inf")) + (self.impl.problem.error_floor if self.impl is not None else 0.0)

    def meets(self, max_error: float) -> bool:
        return self.impl is not None and self.claimed_max <= max_error

    def row(self, picked: bool = False) -> dict:
        r = {"family": self.family, "config": self.config, "picked": picked}
        if self.skipped:
            return {**r, "skipped": self.skipped}
        r.update(describe=self.impl.describe(), model_hash=self.impl.source_hash(), c_hash=files_hash(self.impl.render_c()),
                 model_bytes=self.impl.model_bytes(),
                 pre_max_abs=self.acc["pre_max_abs"], pre_max=self.acc["pre_max"], rms=self.acc["rms"],
                 error_floor=self.impl.problem.error_floor, claimed_max=self.claimed_max,
                 delivered_max_abs=self.acc["delivered_max_abs"], check_points=self.acc["points"],
                 estimate={t: self.est[t] for t in self.est})
        if self.checks:
            r["host"] = self.checks.get("host")
            r["cycles"] = {t: self.checks[t].get("cycles") for t in TARGETS if t in self.checks}
            r["flash_bytes"] = {t: self.checks[t].get("flash_bytes") for t in TARGETS if t in self.checks}
            r["targets"] = {k: v for k, v in self.checks.items() if k != "host"}
        return r


ENOUGH = 4  # a family's ladder stops once this many configurations meet max_error (ladders go cheapest first)
QUICK_POINTS = 60_000  # a configuration is first judged on this many check points


def fit_ladder(problem: Problem, families=None, progress=None, max_error: float | None = None) -> list[Candidate]:
    """Every family's ladder, fitted and measured on the check grid, with cost estimates.

    With ``max_error``, a configuration is first judged on a subsample of the check set (its
    error there is a lower bound); only those that pass it, and each family's most accurate
    one, get the full check. A family's ladder stops once ENOUGH configurations meet it; the
    rest are recorded as not fitted."""
    fams = [f for f in (families or FAMILIES)]
    jobs = [(f, cfg) for f in fams for cfg in FAMILIES[f].ladder(problem)]
    bar = progress(total=len(jobs), desc="fit families", unit="config") if progress else None
    quick = _quick_points(problem) if max_error is not None else None
    out: list[Candidate] = []
    met: dict[str, int] = {}
    growth: dict[str, dict] = {}  # family -> {grown knob value: best error at it}
    for fam, cfg in jobs:
        c = Candidate(fam, cfg)
        within = FAMILIES[fam].grows_within
        gkey = (fam, cfg.get(within)) if within else fam
        stalled = _stalled(FAMILIES[fam].grows_by, cfg, growth.get(gkey, {}))
        if max_error is not None and met.get(fam, 0) >= ENOUGH:
            c.skipped = f"not fitted: {ENOUGH} cheaper configurations of the ladder already meet max_error"
        elif stalled:
            c.skipped = stalled
        else:
            try:
                c.impl = FAMILIES[fam].fit(problem, cfg)
                if quick is not None:
                    c.acc = accuracy(c.impl, quick)
                if quick is None or c.meets(max_error):
                    c.acc = accuracy(c.impl)
                c.est = {t: c.impl.estimate(t) for t in TARGETS}
            except NnikError as exc:
                c.impl, c.skipped = None, str(exc)
            if max_error is not None and c.meets(max_error):
                met[fam] = met.get(fam, 0) + 1
            knob = FAMILIES[fam].grows_by
            if knob and c.impl is not None:
                g = growth.setdefault(gkey, {})
                g[cfg[knob]] = min(g.get(cfg[knob], float("inf")), c.acc["pre_max"])
        out.append(c)
        if bar:
            bar.update(1)
            bar.set_postfix_str(f"{fam}: {c.acc.get('pre_max', float('nan')):.3g}" if c.impl else f"{fam}: -", refresh=False)
    if bar:
        bar.close()
    for fam in fams:  # the most accurate of a family that never met the target gets the full check
        fitted = [c for c in out if c.family == fam and c.impl is not None]
        if fitted and not any(c.meets(max_error) for c in fitted if max_error is not None):
            top = min(fitted, key=lambda c: c.acc["pre_max"])
            if top.acc.get("points") != len(problem.check[0]):
                top.acc = accuracy(top.impl)
    return out


STALL_STEPS = 2  # a grown knob (a polynomial's degree) stops after this many values without gain
STALL_GAIN = 0.9  # a value counts as a gain when it cuts the family's best error below this ratio


def _stalled(knob: str | None, cfg: dict, seen: dict) -> str | None:
    """Why a config is not fitted because its family's growth stopped paying, or None: the last
    STALL_STEPS values of the grown knob below this config's did not cut the best error by 10 %."""
    if not knob or cfg.get(knob) is None:
        return None
    below = sorted(v for v in seen if v < cfg[knob])
    if len(below) <= STALL_STEPS:
        return None
    best_before = min(seen[v] for v in below[:-STALL_STEPS])
    if min(seen[v] for v in below[-STALL_STEPS:]) > STALL_GAIN * best_before:
        return (f"not fitted: {knob} {', '.join(map(str, below[-STALL_STEPS:]))} did not improve the fit "
                f"(best {best_before:.3g} at a lower {knob})")
    return None


def _quick_points(problem: Problem):
    """A fixed subsample of the check set (every corner and edge point kept by the stride)."""
    pts, truth = problem.check
    step = max(1, len(pts) // QUICK_POINTS)
    return pts[::step], truth[::step]


def family_bests(cands: list[Candidate], target: dict) -> dict[str, Candidate]:
    """Per family: the cheapest (estimated cycles on the chip, then flash) configuration that meets
    max_error; if none does, the most accurate one (reported, never picked)."""
    chip, max_err = target["chip"], target["max_error"]
    best: dict[str, Candidate] = {}
    for fam in dict.fromkeys(c.family for c in cands):
        ok = [c for c in cands if c.family == fam and c.impl is not None]
        if not ok:
            continue
        meet = [c for c in ok if c.meets(max_err)]
        if meet:
            best[fam] = min(meet, key=lambda c: (c.est[chip]["cycles"], c.est[chip]["flash_bytes"]))
        else:
            best[fam] = min(ok, key=lambda c: c.acc["pre_max"])
    return best


def verify_candidate(c: Candidate, c_dir: Path, work: Path) -> None:
    """Host (sanitizers) and both simulated chips; results keyed to the C's hash."""
    c.checks["host"] = verify_host(c.impl, c_dir)
    for t in TARGETS:
        c.checks[t] = verify_on_target(c.impl, t, c_dir, work / t / c.family)
        # the portable C99 path (-DNNIK_PORTABLE) must give the same bits on the chip too
        if t in c.impl.portable_checked_on:
            c.checks[f"{t}_portable"] = verify_on_target(c.impl, t, c_dir, work / t / f"{c.family}_portable",
                                                         portable=True, n_inside=60)
        else:
            c.checks[f"{t}_portable"] = {"not_run": c.impl.portable_not_checked_reason}


def _eligible(c: Candidate, target: dict) -> bool:
    chip = target["chip"]
    if not c.meets(target["max_error"]):
        return False
    res = c.checks.get(chip, {})
    if "cycles" not in res or not res.get("bit_exact") or not c.checks["host"]["bit_exact"]:
        return False
    if not all(c.checks[k].get("bit_exact", "not_run" in c.checks[k]) for k in c.checks):
        return False
    if target.get("max_cycles") and res["cycles"] > target["max_cycles"]:
        return False
    if target.get("max_flash_bytes") and res["flash_bytes"] > target["max_flash_bytes"]:
        return False
    return True


def choose(bests: dict[str, Candidate], target: dict) -> Candidate | None:
    chip = target["chip"]
    ok = [c for c in bests.values() if _eligible(c, target)]
    if not ok:
        return None
    return min(ok, key=lambda c: (c.checks[chip]["cycles"], c.checks[chip]["flash_bytes"]))


def choose_most_accurate(bests: dict[str, Candidate], target: dict) -> Candidate | None:
    """With no max_error asked for: the most accurate family best that is bit-exact everywhere it
    ran and within the [target] cycle and flash limits, whether or not it meets the default."""
    ok = [c for c in bests.values() if _eligible(c, {**target, "max_error": float("inf")})]
    return min(ok, key=lambda c: c.acc["pre_max"]) if ok else None


def reach_hint(fitted: list[Candidate], target: dict, problem: Problem | None) -> str:
    """What would reach max_error, as far as the fitted ladder shows: the noise floor of a measured
    machine, a bigger table (bilinear error falls as the cell area, so a table's bytes scale as
    error / max_error), or the search."""
    floor = problem.error_floor if problem is not None else 0.0
    if floor >= target["max_error"]:
        return (f"the reference model of the marks alone is off by about {floor:.3g} (noise and spacing of the "
                f"marks): max_error must exceed it, or measure more marks")
    tables = [c for c in fitted if c.family == "lut" and c.acc.get("pre_max", 0) > 0]
    if tables:
        t = min(tables, key=lambda c: c.acc["pre_max"])
        need = t.impl.model_bytes() * (t.acc["pre_max"] - floor) / max(target["max_error"] - floor, 1e-12)
        limit = target.get("max_flash_bytes")
        chip_flash = CHIP_FLASH[target.get("chip", "avr")]
        if limit and need > limit and need <= chip_flash:
            return (f"a lut finer than {t.impl.describe()} would need about {need / 1024:.1f} KB of table: raise "
                    f"[target] max_flash_bytes ({limit} B)")
        if need > chip_flash:
            return (f"a lut would need about {need / 1024:.0f} KB of table, more than the chip's flash; try "
                    "`nnik search` or a larger max_error")
    return "try `nnik search` over every family's knobs, or a larger max_error"


def no_pick_reason(cands: list[Candidate], bests: dict[str, Candidate], target: dict,
                   problem: Problem | None = None) -> str:
    fitted = [c for c in cands if c.impl is not None]
    if not fitted:
        return "no implementation family could be built: " + "; ".join(f"{c.family}: {c.skipped}" for c in cands)
    top = min(fitted, key=lambda c: c.acc["pre_max"])
    unit_err = f"{top.claimed_max:.4g}"
    if top.claimed_max > target["max_error"]:
        return (f"no implementation meets max_error {target['max_error']:g}: the closest is {top.impl.describe()} "
                f"at {unit_err}; {reach_hint(fitted, target, problem)} (every family's best is in c/alt/)")
    limits = {k: target[k] for k in ("max_cycles", "max_flash_bytes") if target.get(k)}
    meas = ", ".join(f"{c.family} {c.checks.get(target['chip'], {}).get('cycles', float('nan')):.0f} cycles / "
                     f"{c.checks.get(target['chip'], {}).get('flash_bytes', 0)} B"
                     for c in bests.values() if c.meets(target["max_error"]))
    return f"no implementation that meets max_error {target['max_error']:g} fits the limits {limits} on {target['chip']} ({meas})"


def write_choice(c_dir: Path, bests: dict[str, Candidate], pick: Candidate | None) -> None:
    """c/alt/<family>/ for every family's best, c/NAME.{c,h} for the pick, all at once (stale
    files of a family's folder are removed first)."""
    from nnik.files.atomic_write import Staged

    staged = Staged(c_dir)
    for fam, c in bests.items():
        staged.add(c.impl.render_c(), Path(ALT_DIR) / fam)
    if pick is not None:
        staged.add(pick.impl.render_c(), ".")
    alt = c_dir / ALT_DIR
    for fam in bests:
        d = alt / fam
        if d.is_dir():
            for f in d.iterdir():
                if f.is_file() and Path(ALT_DIR) / fam / f.name not in staged.files:
                    f.unlink()
    staged.commit()
