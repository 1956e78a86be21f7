"""A toy family, to show (and test) what adding a family takes: this one folder and one line in
nnik/implementations/__init__.py's REGISTRY (the test registers it with the same loader).

``affine``: each output is ``offset + ((C + A*x + B*y + 2^(s-1)) >> s)``, a least-squares plane in
integers. It is bit-exact, never accurate on a curved IK, and has no fast paths: the portable C
is all there is, so the cost is a fixed guess.
"""

from __future__ import annotations

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.base import Implementation, IntRun
from nnik.implementations.c_common import i32
from nnik.implementations.problem import Problem


class AffineImpl(Implementation):
    family = "affine"
    doc = "a least-squares plane per output (a toy family for the tests)"

    def __init__(self, problem: Problem, config: dict, coef: np.ndarray | None = None):
        super().__init__(problem, config)
        self.coef = coef  # (2, 3) int64: C, A, B per output

    @classmethod
    def ladder(cls, problem: Problem) -> list[dict]:
        return [{"shift": 12}, {"shift": 20}]

    @classmethod
    def fit(cls, problem: Problem, config: dict) -> "AffineImpl":
        s = int(config["shift"])
        x, q = problem.fit_samples(41)
        m = np.column_stack([np.ones(len(x)), x])
        sol = np.linalg.lstsq(m, q, rcond=None)[0]  # (3, 2)
        coef = np.rint(sol.T * 2.0**s).astype(np.int64)
        if np.any(np.abs(coef) >= 2**31):
            raise NnikError(f"affine: shift {s} does not fit int32 coefficients")
        return cls(problem, config, coef)

    def run(self, in_units: np.ndarray) -> IntRun:
        x, flags = self.problem.clamp(in_units)
        num = self.coef[:, 0][None, :] + x[:, :1] * self.coef[:, 1][None, :] + x[:, 1:] * self.coef[:, 2][None, :]
        s = int(self.config["shift"])
        return IntRun(pre=num / 2.0**s, out=self.problem.finish(num, s), flags=flags)

    def render_source(self) -> str:
        p, s = self.problem, int(self.config["shift"])
        lines = [f'#include "{p.name}.h"', "",
                 f"int8_t {p.name}_ik(const int32_t in_um[2], int32_t out[2])", "{",
                 "    int8_t clamped = 0;", "    int32_t x = in_um[0], y = in_um[1];", "    int64_t n;"]
        for a, v in enumerate(("x", "y")):
            lines += [f"    if ({v} < {i32(p.lo[a])}) {{ {v} = {i32(p.lo[a])}; clamped = 1; }}",
                      f"    else if ({v} > {i32(p.hi[a])}) {{ {v} = {i32(p.hi[a])}; clamped = 1; }}"]
        for j, (c, a, b) in enumerate(self.coef.tolist()):
            lines += [f"    n = (int64_t){i32(c)} + (int64_t){i32(a)} * x + (int64_t){i32(b)} * y;",
                      f"    n = (n + ((int64_t)1 << {s - 1})) >> {s};"]
            if p.code_range is not None:
                lo, hi = p.code_range
                lines.append(f"    if (n < {lo}) n = {lo}; else if (n > {hi}) n = {hi};")
            lines.append(f"    out[{j}] = (int32_t)n;")
        return "\n".join(lines + ["    return clamped;", "}", ""])

    def estimate(self, target: str) -> dict:
        return {"cycles": 2000.0, "flash_bytes": 400, "ram_bytes": 16, "validated": False}

    def model_bytes(self) -> int:
        return 24


IMPLEMENTATION = AffineImpl
