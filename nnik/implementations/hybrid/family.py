"""The ``hybrid`` family: an exact affine base (least squares) evaluated in int32, plus the
residual in a ``lut`` table (:mod:`nnik.implementations.lut.table`). The residual is small, so
the table's int16 entries carry many more fractional bits than a full table's.

Integer contract (per output o; tx, ty = the table's index coordinates after the clamp,
unsigned: x - lo_x, or |x| on an axis the table folds):
    base = C + Ax tx + Ay ty               int32, Q``G`` (|Ax|, |Ay| < 2^coef_bits; |base| < 2^31)
    acc  = the residual table's accumulator, Q``s_t`` (not yet negated)
    total = base + (acc >> (s_t - G))      (or acc 2^(G - s_t) when s_t < G)
    total = -total for an odd output whose folded input is negative
    out = offset + ((total + 2^(G-1)) >> G), then the DAC clamp; pre = offset + total / 2^G.
The table is fitted to the exact residual q - offset - base / 2^G of the quantised base.

Symmetry: where the exact IK is even or odd in an axis whose domain is symmetric about 0, the
base is fitted in folded coordinates with only the terms that keep that symmetry (an output odd
in x has no constant and no y term: it must vanish at x = 0), so the residual table folds as the
``lut`` family's does (a half or quarter table), and an output that depends on one input only
keeps a 1-D residual table.

Knobs: ``k``, ``bits``, ``W``, ``fit``, ``symmetry``, ``separable`` as in ``lut``, ``base`` =
"affine", ``coef_bits`` = 16 | 8: the width of |Ax|, |Ay| (8 halves the base's multiplies; the
coarser slope is a linear ramp the residual table absorbs exactly).
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.c_common import i32
from nnik.implementations.lut.family import LutImpl, cell_exponents, cell_ladder, folded_data, table_budget, table_for
from nnik.implementations.lut.table import Table, base_terms, dependence
from nnik.implementations.problem import Problem

DEFAULTS = {"bits": 16, "W": 16, "fit": "lsq", "base": "affine", "coef_bits": 16, "symmetry": True,
            "separable": True}


def affine_lsq(t: np.ndarray, q: np.ndarray, use: np.ndarray) -> np.ndarray:
    """(2, 3) float coefficients [c, ax, ay] per output of the least-squares affine map, with
    only the terms `use` allows (the others 0)."""
    m = np.column_stack([np.ones(len(t)), t[:, 0], t[:, 1]])
    coef = np.zeros((2, 3))
    for o in range(2):
        if use[o].any():
            coef[o, use[o]] = np.linalg.lstsq(m[:, use[o]], q[:, o], rcond=None)[0]
    return coef


class HybridImpl(LutImpl):
    family = "hybrid"
    doc = "exact affine base in int32 plus a residual bilinear table"

    def __init__(self, problem: Problem, config: dict, table: Table | None = None, base=None, G=None,
                 offset=None):
        super().__init__(problem, config, table)
        self.base = base  # (2, 3) int64: C, Ax, Ay
        self.G = G  # (2,) base fractional bits
        self.offset = offset  # (2,) int

    @classmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        """Residual tables with cells halving from about 4 nodes per stored axis while they fit the
        flash budget (lut.table_budget):
        an 8-bit cell fraction with 8-bit base slopes (fastest) and Q16 with 16-bit slopes
        (minimax nodes up to 14 per axis)."""
        span = cls.stored_span(problem)
        out = []
        for k in cell_ladder(span, table_budget(problem), dependence(problem, True)):
            # minimax only on exact samples of small tables (on measured rows it fits the noise)
            small = problem.analytic and max((span[a] >> k[a]) + 2 for a in range(2)) <= 14
            out += [{"k": k, "bits": 16, "W": 8, "fit": "lsq", "base": "affine", "coef_bits": 8},
                    {"k": k, "bits": 16, "W": 16, "fit": "minimax" if small else "lsq", "base": "affine",
                     "coef_bits": 16}]
        return out

    @classmethod
    def fit(cls, problem: Problem, config: dict) -> "HybridImpl":
        cfg = {**DEFAULTS, **config}
        if cfg["base"] != "affine":
            raise NnikError(f"unknown hybrid base {cfg['base']!r} (affine)")
        if cfg["coef_bits"] not in (8, 16):
            raise NnikError(f"hybrid coef_bits {cfg['coef_bits']!r}: must be 8 or 16")
        a_max = (1 << cfg["coef_bits"]) - 1  # |A|: 8 bits halves the base's multiplies
        cfg["k"] = cell_exponents(cfg)
        d = folded_data(problem, cfg)
        t, qf = d.t, d.q  # folded: an output that is not odd keeps its values, so its range too
        span = np.array(d.grid.span, dtype=np.float64)
        use = base_terms(d.odd, d.dep)
        coef = affine_lsq(t, qf, use)
        offset = np.array([0 if d.odd[o].any() else int(np.rint((qf[:, o].max() + qf[:, o].min()) / 2))
                           for o in range(2)], dtype=np.int64)
        base, G = [], []
        for o in range(2):
            c, ax, ay = coef[o]
            c = c - offset[o] if use[o, 0] else 0.0
            amp = float(np.abs(qf[:, o] - offset[o]).max()) * 1.5 + 1.0
            g = None
            for gg in range(24, -1, -1):
                A = np.rint(np.array([ax, ay]) * 2.0**gg)
                C = np.rint(c * 2.0**gg)
                if np.abs(A).max() > a_max:
                    continue
                if abs(C) + np.abs(A) @ span + amp * 2.0**gg + 2.0**gg < 2.0**30:
                    g = gg
                    break
            if g is None:
                raise NnikError(f"affine base of output {o} does not fit int32 with int16 coefficients")
            base.append([int(C), int(A[0]), int(A[1])])
            G.append(g)
        base = np.array(base, dtype=np.int64)
        G = np.array(G)
        bval = (base[:, 0][None, :] + t[:, :1] * base[:, 1][None, :] + t[:, 1:] * base[:, 2][None, :]) / 2.0**G
        tab = table_for(problem, cfg, d, qf - offset - bval)
        for o in range(2):  # the table's offset (0 for an odd output) moves into the base constant
            base[o, 0] += int(tab.offset[o]) << int(G[o])
        tab.offset = (0, 0)
        im = cls(problem, cfg, tab, base, G, offset)
        im._check_range()
        return im

    # ---- integer model -----------------------------------------------------------------------------
    @property
    def align(self) -> list[int]:
        return [int(self.table.shift[o] - self.G[o]) for o in range(2)]

    def _check_range(self) -> None:
        """|base| is largest at a corner of the domain (it is affine); the table adds at most
        max|e| 2^-fb; the sum and the rounding half must stay below 2^31."""
        span = self.table.grid.span
        corners = np.array([[0, 0], [span[0], 0], [0, span[1]], [span[0], span[1]]], dtype=np.float64)
        for o in range(2):
            b = np.abs(self.base[o, 0] + corners @ self.base[o, 1:].astype(np.float64)).max()
            tab = (np.abs(self.table.ent[o]).max() + 1) * 2.0 ** (int(self.G[o]) - self.table.fb[o]) + 1
            if b + tab + 2.0 ** self.G[o] >= 2**31:
                raise NnikError(f"hybrid output {o} overflows int32 (base {b:.4g} + table {tab:.4g})")

    def total(self, in_units: np.ndarray) -> np.ndarray:
        c, _ = self.problem.clamp(in_units)
        acc = self.table.acc(c, flip=False)
        t, neg = self.table.grid.t(c)
        out = np.empty(acc.shape, dtype=np.int64)
        for o in range(2):
            b = self.base[o, 0] + self.base[o, 1] * t[:, 0] + self.base[o, 2] * t[:, 1]
            al = self.align[o]
            tot = b + ((acc[:, o] >> al) if al >= 0 else acc[:, o] * (1 << -al))
            out[:, o] = np.where(self.table.flips(neg, o), -tot, tot)
        return out

    def run(self, in_units: np.ndarray):
        from nnik.implementations.base import IntRun

        p = self.problem
        _, flags = p.clamp(in_units)
        tot = self.total(in_units)
        pre = np.empty(tot.shape)
        out = np.empty(tot.shape, dtype=np.int64)
        for o in range(2):
            pre[:, o] = self.offset[o] + tot[:, o] / 2.0 ** self.G[o]
            out[:, o] = p.finish(tot[:, o], int(self.G[o]), int(self.offset[o]))
        return IntRun(pre=pre, out=out, flags=flags)

    # ---- C ---------------------------------------------------------------------------------------------
    def final_stage(self) -> dict:
        G = [int(g) for g in self.G]
        base_c = [f"(uint32_t){i32(self.base[o, 0])} + (uint32_t)({i32(self.base[o, 1])} * (int32_t)tx)"
                  f" + (uint32_t)({i32(self.base[o, 2])} * (int32_t)ty)" for o in range(2)]
        return {"final_shift": G, "final_off": [i32(v) for v in self.offset],
                "final_off_int": [int(v) for v in self.offset],
                "half": [i32(1 << (g - 1)) if g > 0 else None for g in G], "base": True, "base_c": base_c,
                "align": self.align, "G": G}

    def render_source(self) -> str:
        from nnik.emit.templating import environment
        from nnik.implementations.hybrid import asm as hybrid_asm
        from nnik.implementations.lut import avr as lut_avr
        from nnik.implementations.lut import p18 as lut_p18
        from nnik.implementations.lut.c import table_ctx
        from nnik.implementations.c_common import comment_safe

        p = self.problem
        ctx = dict(name=p.name, NAME=p.name.upper(), scenario=comment_safe(p.scn.name), family=self.family,
                   title=comment_safe(self.describe()), outputs=p.outputs,
                   lo=[i32(v) for v in p.lo], hi=[i32(v) for v in p.hi], code_range=p.code_range,
                   code_lo=i32(p.code_range[0]) if p.code_range else None,
                   code_hi=i32(p.code_range[1]) if p.code_range else None, **table_ctx(p, self.table),
                   **self.final_stage())
        ctx["avr_body"] = hybrid_asm.avr_body(self, ctx)
        ctx["p18_body"] = hybrid_asm.p18_body(self, ctx)
        return environment().get_template("lut2_ik.c.j2").render(**ctx)

    def avr_lines(self, ctx) -> list[str]:
        from nnik.implementations.hybrid import asm as hybrid_asm

        return hybrid_asm.avr_lines(self, ctx)

    def p18_items(self, ctx) -> list:
        from nnik.implementations.hybrid import asm as hybrid_asm

        return hybrid_asm.p18_items(self, ctx)

    def model_bytes(self) -> int:
        return self.table.nbytes

    def estimate(self, target: str) -> dict:
        from nnik.implementations.lut.cost import estimate

        return estimate(self, target)

    def describe(self) -> str:
        return f"hybrid affine + residual lut {self.table_text()}"


IMPLEMENTATION = HybridImpl
