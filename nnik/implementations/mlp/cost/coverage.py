"""Coverage of the fast kernel's calibration, a developer tool (no simulator).

The calibration networks must span every combination of per-call counts the search can
propose (nnik.implementations.mlp.cost.span): code paths, shift regimes of the tanh input, output and input
stages, int8 and int16 weights, residual bases, DAC clamps, tanh replacements.
``coverage_specs`` picks them from seeded pools of synthetic networks (widths outside the
judged 4-16, tanh replacements, formats moved by the weight gain and the output scale): a pool
network joins when it widens the span on a target where it can be measured.  The result is
fixed: ``synthetic.COVERAGE_SPECS`` holds the list, and tests/bench/mlp_cost check that random search
architectures fall inside the span of the calibration set.

    python3 -m nnik.implementations.mlp.cost.coverage          # print the picked specs
"""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp.cost.fast_features import fast_path
from nnik.implementations.mlp.cost.span import structure_row
from nnik.implementations.mlp.cost.synthetic import SEARCH_TANHS, CalSpec, synthetic_model

TARGETS = ("avr", "pic18")
POOL_SEEDS = (4242,)
# SDCC compiles the unrolled C of a fast network slowly: on PIC18 its C path is calibrated on
# hidden sizes up to this only (nnik.bench.mlp_cost.measure skips larger ones)
PIC18_C_MAX_HIDDEN = 3


def measurable(spec: CalSpec, im, target: str) -> bool:
    return not (target == "pic18" and fast_path(im, target) == "c" and max(spec.hidden) > PIC18_C_MAX_HIDDEN)


def pool(n: int, seed: int) -> list[CalSpec]:
    rng = np.random.default_rng(seed)
    shapes = ((3,), (17,), (20,), (3, 3), (3, 17), (17, 3), (3, 20), (2, 3), (3, 2), (1, 3), (3, 1))
    out = []
    s0 = 5000 + 10_000 * (seed - POOL_SEEDS[0])  # distinct network seeds per pool
    for i in range(n):
        out.append(CalSpec(str(rng.choice(("galvo", "galvo_small", "corexy", "dual"))),
                           shapes[int(rng.integers(0, len(shapes)))], tanh=str(rng.choice(SEARCH_TANHS)),
                           weight_bits=int(rng.choice((8, 16))), seed=s0 + i,
                           gain=float(rng.choice((0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0, 1.5, 2.5))),
                           out_scale=float(rng.choice((1.0, 1.0, 0.01, 0.1, 3.0, 30.0))), n_vec=12))
    # the assembly bodies (one layer, the kernel's own tanh) of residual networks: their output
    # stage in assembly or finished in C, by the formats
    for i in range(n // 4):
        out.append(CalSpec(str(rng.choice(("corexy", "dual"))), ((3,), (17,), (20,))[int(rng.integers(0, 3))],
                           tanh="", weight_bits=int(rng.choice((8, 16))), seed=s0 + 4000 + i,
                           gain=float(rng.choice((0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0, 1.5, 2.5))),
                           out_scale=float(rng.choice((1.0, 0.1, 3.0))), n_vec=12))
    return out


class Span:
    """Row spaces of count vectors, one per target."""

    def __init__(self):
        self.rows = {t: [] for t in TARGETS}

    @staticmethod
    def _rank(rows) -> int:
        names = sorted({k for r in rows for k in r})
        if not rows:
            return 0
        return int(np.linalg.matrix_rank(np.array([[r.get(k, 0.0) for k in names] for r in rows])))

    def add(self, spec: CalSpec, force: bool = False) -> bool:
        """Keep the spec when it widens the span on a target where it is measured (force: keep
        it regardless); returns whether it was kept."""
        im = synthetic_model(spec, kernel="fast")
        rows = {t: structure_row(im, False, t) for t in TARGETS if measurable(spec, im, t)}
        keep = force or any(self._rank(self.rows[t] + [r]) > self._rank(self.rows[t]) for t, r in rows.items())
        if keep:
            for t, r in rows.items():
                self.rows[t].append(r)
        return keep


def coverage_specs(base: list[CalSpec], seed: int, n_pool: int = 700) -> list[CalSpec]:
    """Networks of one pool that widen the span of `base` (in pool order)."""
    span = Span()
    for sp in base:
        span.add(sp, force=True)
    return [sp for sp in pool(n_pool, seed) if span.add(sp)]


if __name__ == "__main__":
    import sys

    from nnik.implementations.mlp.cost.synthetic import calibration_specs

    # each pool gives a set that spans on its own (more pools: every direction covered more than once)
    for seed in [int(a) for a in sys.argv[1:]] or POOL_SEEDS:
        for sp in coverage_specs(calibration_specs("fast", coverage=False), seed):
            print(f"    CalSpec({sp.scenario!r}, {sp.hidden!r}, tanh={sp.tanh!r}, weight_bits={sp.weight_bits}, "
                  f"seed={sp.seed}, gain={sp.gain:g}, out_scale={sp.out_scale:g}, n_vec={sp.n_vec}),")
