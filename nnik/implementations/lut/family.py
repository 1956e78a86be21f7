"""The ``lut`` family: a bilinear table with power-of-two cells, node values fitted by least
squares or minimax over dense points, a half or quarter table where the exact IK's own
symmetry allows it (see :mod:`nnik.implementations.lut.table` for the integer contract).

Knobs (``config``):
    k         [kx, ky]: cell size exponents, cells of 2^k input units
    bits      16 | 32: entry width
    W         16 | 8: bits of the cell fraction (8 is cheaper, coarser within a cell)
    fit       "lsq" | "minimax"
    symmetry  true | false: fold the axes the numerical symmetry check allows
    separable true | false: a 1-D table for an output the exact IK shows to depend on one
              input only (e.g. a galvo's y mirror)
    fb        optional: force the fractional bits of the entries (else range analysis)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.c_common import comment_safe, i32
from nnik.implementations.lut.c import table_ctx
from nnik.implementations.lut.table import MAX_NODES, Grid, Table, dependence, fit_nodes, fold_plan, quantise
from nnik.implementations.problem import Problem

DEFAULTS = {"bits": 16, "W": 16, "fit": "lsq", "symmetry": True, "separable": True}


def fit_points(problem: Problem, grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Points (input units) and targets to fit: integer points of a dense grid (at least 8 per
    cell) plus the training set, with the exact IK; measured rows as they are."""
    if not problem.analytic:
        return problem.fit_samples()
    n = int(min(1201, max(161, 8 * max(grid.n) + 1)))
    key = ("lut_fit", n)
    if key not in problem.cache:
        p, _ = problem.fit_samples(n)
        pts = np.unique(np.clip(np.rint(p), problem.lo, problem.hi).astype(np.int64), axis=0)
        problem.cache[key] = (pts, problem.truth(pts))
    return problem.cache[key]


def fold_targets(grid: Grid, odd: np.ndarray, pts: np.ndarray, q: np.ndarray):
    """Fold points and targets onto the stored part of the table (odd outputs change sign)."""
    t = np.empty(pts.shape, dtype=np.float64)
    qf = np.array(q, dtype=np.float64)
    for a in range(2):
        if grid.fold[a]:
            t[:, a] = np.abs(pts[:, a])
            neg = pts[:, a] < 0
            for o in range(2):
                if odd[o, a]:
                    qf[neg, o] = -qf[neg, o]
        else:
            t[:, a] = pts[:, a] - grid.origin[a]
    return t, qf


@dataclass
class FoldedData:
    """A config's grid and its fit data on the stored part of the table: folded coordinates t,
    folded targets q (odd outputs sign-flipped), the odd mask and the per-output dependence."""

    grid: Grid
    odd: np.ndarray
    dep: tuple[str, str]
    t: np.ndarray
    q: np.ndarray


def folded_data(problem: Problem, cfg: dict) -> FoldedData:
    """Grid (with the folds the symmetry check allows) and the folded fit points of a config."""
    fold, odd = fold_plan(problem, bool(cfg.get("symmetry", True)))
    grid = Grid.make(problem.lo, problem.hi, cfg["k"], fold, int(cfg.get("W", 16)))
    pts, q = fit_points(problem, grid)
    t, qf = fold_targets(grid, odd, np.asarray(pts, dtype=np.float64), q)
    return FoldedData(grid, odd, dependence(problem, bool(cfg.get("separable", True))), t, qf)


def table_for(problem: Problem, cfg: dict, d: FoldedData, values: np.ndarray) -> Table:
    """Node fit and range analysis of `values` (N, 2) at d.t: the IK itself (lut) or the
    residual over a base (hybrid)."""
    vals, _ = fit_nodes(d.grid, d.t, values, d.odd, cfg.get("fit", "lsq"), measured=not problem.analytic, dep=d.dep)
    return quantise(d.grid, vals, int(cfg.get("bits", 16)), d.odd, cfg.get("fb"), dep=d.dep)


def build_table(problem: Problem, cfg: dict) -> Table:
    """Grid, fit and range analysis for a config."""
    d = folded_data(problem, cfg)
    return table_for(problem, cfg, d, d.q)


def k_for_nodes(span: int, nodes: int) -> int:
    """The cell exponent that gives about `nodes` nodes over `span`."""
    return max(0, int(math.ceil(math.log2(max(1.0, span / max(1, nodes - 1))))))


def cell_exponents(cfg: dict) -> list[int]:
    """The config's k as two ints, or a one-line NnikError."""
    if cfg.get("bits", 16) not in (16, 32):
        raise NnikError(f"entry bits {cfg.get('bits')!r}: must be 16 or 32")
    if cfg.get("W", 16) not in (8, 16):
        raise NnikError(f"weight bits {cfg.get('W')!r}: must be 8 or 16")
    k = cfg.get("k")
    if not isinstance(k, (list, tuple)) or len(k) != 2 or not all(isinstance(v, (int, np.integer)) for v in k):
        raise NnikError(f"table config needs k = [kx, ky], two integer cell size exponents (got {k!r})")
    return [int(v) for v in k]


CHIP_FLASH = {"avr": 32 * 1024, "pic18": 32 * 1024}  # ATmega328P, PIC18F452
TABLE_FLASH_SHARE = 2  # with no [target] max_flash_bytes, a table may take 1/2 of the chip's flash:
# the rest is the firmware's (nnik's G-code firmware takes about 15 KB on the Uno)


def table_budget(problem: Problem) -> int:
    """Flash bytes a table may take: [target] max_flash_bytes, else half the chip's flash."""
    tg = problem.scn.target
    return int(tg.get("max_flash_bytes") or CHIP_FLASH[tg.get("chip", "avr")] // TABLE_FLASH_SHARE)


def table_entries(span: list[int], k: list[int], dep=("xy", "xy")) -> int:
    """Entries of a two-output table with cells 2^k over the stored span (1-D outputs store one row)."""
    n = [(span[a] >> k[a]) + 2 for a in range(2)]
    return sum(n[0] * n[1] if d == "xy" else n["xy".index(d)] for d in dep)


def cell_ladder(span: list[int], budget_bytes: int, dep=("xy", "xy"), first_nodes: int = 4) -> list[list[int]]:
    """Cell exponents per axis, halving the cells from about `first_nodes` nodes per axis while an
    int16 table of that size fits `budget_bytes` (and the one-byte cell index). The target and the
    chip decide how far a ladder grows, not a node count tuned to a scenario."""
    k0 = [k_for_nodes(s, first_nodes) for s in span]
    out = []
    for step in range(24):
        k = [max(0, k0[a] - step) for a in range(2)]
        if max((span[a] >> k[a]) + 2 for a in range(2)) > MAX_NODES or 2 * table_entries(span, k, dep) > budget_bytes:
            break
        out.append(k)
        if k == [0, 0]:
            break
    return out


class LutImpl(Implementation):
    family = "lut"
    doc = "bilinear table, power-of-two cells, least-squares or minimax nodes, symmetry folds"

    def __init__(self, problem: Problem, config: dict, table: Table | None = None):
        super().__init__(problem, config)
        self.table = table

    # ---- fitting -------------------------------------------------------------------------------
    @classmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        """Cells halving from about 4 nodes per stored axis while the table fits the flash budget
        (:func:`table_budget`); per size an int16
        table with an 8-bit cell fraction (fastest), a Q16 int16 table (minimax nodes up to 14
        per axis) and a Q16 int32 table (wide outputs, DACs)."""
        span = cls.stored_span(problem)
        budget, dep = table_budget(problem), dependence(problem, True)
        out = []
        for k in cell_ladder(span, budget, dep):
            # minimax only on exact samples of small tables (on measured rows it fits the noise)
            small = problem.analytic and max((span[a] >> k[a]) + 2 for a in range(2)) <= 14
            out += [{"k": k, "bits": 16, "W": 8, "fit": "lsq", "symmetry": True},
                    {"k": k, "bits": 16, "W": 16, "fit": "minimax" if small else "lsq", "symmetry": True}]
            if 4 * table_entries(span, k, dep) <= budget:
                out.append({"k": k, "bits": 32, "W": 16, "fit": "lsq", "symmetry": True})
        return out

    @staticmethod
    def stored_span(problem: Problem, symmetry: bool = True) -> list[int]:
        """Span of the stored table per axis (after the symmetry folds), input units."""
        fold, _ = fold_plan(problem, symmetry)
        return [max(int(problem.hi[a]), -int(problem.lo[a])) if fold[a] else int(problem.hi[a] - problem.lo[a])
                for a in range(2)]

    @classmethod
    def fit(cls, problem: Problem, config: dict) -> "LutImpl":
        cfg = {**DEFAULTS, **config}
        cfg["k"] = cell_exponents(cfg)
        return cls(problem, cfg, build_table(problem, cfg))

    # ---- the integer model ------------------------------------------------------------------------
    def run(self, in_units: np.ndarray) -> IntRun:
        p = self.problem
        c, flags = p.clamp(in_units)
        acc = self.table.acc(c)
        pre = np.empty(acc.shape)
        out = np.empty(acc.shape, dtype=np.int64)
        for o in range(2):
            s = self.table.shift[o]
            pre[:, o] = self.table.offset[o] + acc[:, o] / 2.0**s
            out[:, o] = p.finish(acc[:, o], s, self.table.offset[o])
        return IntRun(pre=pre, out=out, flags=flags)

    # ---- C ----------------------------------------------------------------------------------------
    def final_stage(self) -> dict:
        t = self.table
        return {"final_shift": list(t.shift), "final_off": [i32(v) for v in t.offset],
                "final_off_int": [int(v) for v in t.offset],
                "half": [i32(1 << (s - 1)) if s > 0 else None for s in t.shift], "base": None}

    def render_source(self) -> str:
        from nnik.implementations.lut import avr as lut_avr
        from nnik.implementations.lut import p18 as lut_p18
        from nnik.emit.templating import environment

        p = self.problem
        t = self.table
        ctx = dict(name=p.name, NAME=p.name.upper(), scenario=comment_safe(p.scn.name), family=self.family,
                   title=comment_safe(self.describe()), outputs=p.outputs,
                   lo=[i32(v) for v in p.lo], hi=[i32(v) for v in p.hi], code_range=p.code_range,
                   code_lo=i32(p.code_range[0]) if p.code_range else None,
                   code_hi=i32(p.code_range[1]) if p.code_range else None, **table_ctx(p, t),
                   **self.final_stage())
        ctx["avr_body"] = lut_avr.body(self, ctx)
        ctx["p18_body"] = lut_p18.body(self, ctx)
        return environment().get_template("lut2_ik.c.j2").render(**ctx)

    def avr_lines(self, ctx) -> list[str]:
        from nnik.implementations.lut import avr as lut_avr

        return lut_avr.lines(self, ctx)

    def p18_items(self, ctx) -> list:
        from nnik.implementations.lut import p18 as lut_p18

        return lut_p18.items(self, ctx)

    # ---- cost -------------------------------------------------------------------------------------
    def model_bytes(self) -> int:
        return self.table.nbytes

    def estimate(self, target: str) -> dict:
        from nnik.implementations.lut.cost import estimate

        return estimate(self, target)

    def table_text(self) -> str:
        """The table in words: nodes, 1-D outputs, entries, cells, fraction, fit, folds."""
        t = self.table
        g = t.grid
        fold = "".join(a for a, f in zip("xy", g.fold) if f)
        sym = f", folded in {fold}" if fold else ""
        one = "".join(f", {self.problem.outputs[o]} 1-D in {t.dep[o]}" for o in range(2) if t.dep[o] != "xy")
        return (f"{g.n[0]}x{g.n[1]}{one} int{t.bits} (cells 2^{g.k[0]} x 2^{g.k[1]}, Q{g.W} fraction, "
                f"{self.config.get('fit', 'lsq')}{sym})")

    def describe(self) -> str:
        return f"lut {self.table_text()}"


IMPLEMENTATION = LutImpl
