"""The contract every IK implementation family is fitted to and judged on.

A :class:`Problem` is built once per scenario. It fixes

* the C API every family emits: ``int8_t NAME_ik(const int32_t in_um[2], int32_t out[2])``.
  Inputs are integers in the scenario's input unit (``[export] input_unit_um`` micrometres,
  default 1), clamped to the domain ``[lo, hi]`` (the workspace rounded inward to whole input
  units); the return value is 1 if an input was clamped, else 0. Outputs are whole actuator units
  (microsteps or DAC LSB, counted from rest), rounded half up from the pre-rounding value, and for
  a DAC clamped to its code range;
* the data a family may fit on (``fit_in``/``fit_q``: dense exact samples for an analytic
  mechanism, the training rows for measured data);
* the check set its accuracy is judged on (``check``): a dense grid of 1001 x 1001 input points,
  4001 points along each edge, the corners and 200,000 random integer points, labelled with the
  exact IK, or the held-out rows of measured data.

A measured machine with a ``reference`` (nnik.machine.reference, fitted to the marks) is compiled like an
analytic one: ``truth()`` is the reference, the check set is the dense set restricted to the
marks' convex hull, and ``error_floor`` (the reference's estimated max error against the machine)
is what selection adds to an implementation's error before comparing it with ``max_error``.

Accuracy is always pre-rounding ``max |pre - truth|`` in output units on the check set.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from nnik.errors import NnikError
from nnik.machine.scenario import Scenario

CHECK_GRID = 1001  # dense check grid per axis (inclusive of both edges)
EDGE_POINTS = 4001  # points along each domain edge
CHECK_RANDOM = 200_000  # random integer points checked besides the grid
CHECK_SEED = 20261123  # their seed: no family fits on them
MAX_FIT_ROWS = 50_000  # measured rows a family fits on (a fixed random subset beyond this)


def domain_units(scn: Scenario, unit_um: float) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) int64 per input axis in input units: the workspace rounded inward."""
    lo = np.ceil(np.round(scn.workspace.lo * 1000.0 / unit_um, 6)).astype(np.int64)
    hi = np.floor(np.round(scn.workspace.hi * 1000.0 / unit_um, 6)).astype(np.int64)
    return lo, hi


def dense_grid(lo: np.ndarray, hi: np.ndarray, n: int = CHECK_GRID, edge: int = EDGE_POINTS) -> np.ndarray:
    """(M, 2) int64: an n x n grid over [lo, hi] (both edges included), every corner, and `edge`
    points along each of the four edges."""
    gx = np.unique(np.rint(np.linspace(lo[0], hi[0], n)).astype(np.int64))
    gy = np.unique(np.rint(np.linspace(lo[1], hi[1], n)).astype(np.int64))
    grid = np.stack(np.meshgrid(gx, gy, indexing="xy"), -1).reshape(-1, 2)
    ex = np.unique(np.rint(np.linspace(lo[0], hi[0], edge)).astype(np.int64))
    ey = np.unique(np.rint(np.linspace(lo[1], hi[1], edge)).astype(np.int64))
    edges = np.concatenate([
        np.stack([ex, np.full_like(ex, lo[1])], 1), np.stack([ex, np.full_like(ex, hi[1])], 1),
        np.stack([np.full_like(ey, lo[0]), ey], 1), np.stack([np.full_like(ey, hi[0]), ey], 1),
    ])
    return np.unique(np.concatenate([grid, edges]), axis=0)


@dataclass
class Problem:
    """One scenario's IK, as every implementation family sees it (see the module docstring)."""

    scn: Scenario
    dataset: object  # nnik.machine.data.Dataset: the scenario's samples (the MLP trains on them)
    unit_um: float = 1.0
    cache: dict = field(default_factory=dict)  # families may keep fitted artefacts here (e.g. trained MLPs)
    reference: object | None = None  # nnik.machine.reference.Reference of a measured machine

    @property
    def name(self) -> str:
        return self.scn.name

    @property
    def outputs(self) -> list[str]:
        return self.scn.outputs

    @property
    def unit(self) -> str:
        return self.scn.unit

    @property
    def analytic(self) -> bool:
        """truth() is defined at every input: the exact IK, or a measured machine's reference."""
        return bool(self.scn.mechanism.analytic) or self.reference is not None

    @property
    def measured(self) -> bool:
        return not self.scn.mechanism.analytic

    @property
    def error_floor(self) -> float:
        """Added to an implementation's error against truth() before it is judged against
        max_error: the reference's estimated max error against the machine (0 for exact IK)."""
        return self.reference.error_max if self.reference is not None else 0.0

    @property
    def code_range(self) -> tuple[int, int] | None:
        return self.scn.actuator.code_range

    @cached_property
    def domain(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = domain_units(self.scn, self.unit_um)
        if np.any(hi <= lo):
            raise NnikError("workspace is narrower than one input unit", self.scn.source, "[export] input_unit_um")
        if np.any(np.abs(np.concatenate([lo, hi])) >= 2**31 - 1):
            raise NnikError("workspace in input units does not fit int32", self.scn.source, "[export] input_unit_um")
        return lo, hi

    @property
    def lo(self) -> np.ndarray:
        return self.domain[0]

    @property
    def hi(self) -> np.ndarray:
        return self.domain[1]

    def to_mm(self, in_units: np.ndarray) -> np.ndarray:
        return np.asarray(in_units, dtype=np.float64) * (self.unit_um / 1000.0)

    def to_units(self, p_mm: np.ndarray) -> np.ndarray:
        """Positions (mm) -> integer input units (round to nearest)."""
        return np.rint(np.asarray(p_mm, dtype=np.float64) * (1000.0 / self.unit_um)).astype(np.int64)

    def truth(self, in_units: np.ndarray) -> np.ndarray:
        """Exact IK (or the measured machine's reference) in actuator units at integer inputs."""
        from nnik.machine.data import exact_targets

        if self.reference is not None:
            return self.reference(self.to_mm(in_units))
        if not self.analytic:
            raise NnikError("a measured machine has no exact IK off its rows", self.scn.source)
        return exact_targets(self.scn, self.to_mm(in_units))

    def clamp(self, in_units: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The C's domain clamp -> (clamped int64 (N, 2), flags int64 (N,))."""
        x = np.asarray(in_units, dtype=np.int64).reshape(-1, 2)
        c = np.clip(x, self.lo, self.hi)
        return c, np.any(c != x, axis=1).astype(np.int64)

    @cached_property
    def check(self) -> tuple[np.ndarray, np.ndarray]:
        """(inputs int64 (M, 2), truth (M, 2)): the dense grid, or the held-out rows."""
        if self.analytic:
            # the grid's regular spacing can miss the worst residues of the input quantisation,
            # so random integer points are checked too
            rnd = np.random.default_rng(CHECK_SEED).integers(self.lo, self.hi + 1, (CHECK_RANDOM, 2))
            pts = np.concatenate([dense_grid(self.lo, self.hi), rnd])
            if self.reference is not None:  # the reference is known only inside the marks' hull
                pts = pts[self.reference.hull.inside(self.to_mm(pts), tol_mm=1e-6)]
            return pts, self.truth(pts)
        ds = self.dataset
        pts = self.to_units(ds.p["test"])
        keep = np.all((pts >= self.lo) & (pts <= self.hi), axis=1)
        return pts[keep], ds.q["test"][keep]

    def fit_samples(self, n_per_axis: int = 161) -> tuple[np.ndarray, np.ndarray]:
        """(inputs float64 in input units (N, 2), exact outputs (N, 2)) to fit on: a dense
        n x n grid plus the training set for analytic mechanisms; training + validation rows for
        measured data."""
        ds = self.dataset
        if not self.analytic:
            p = np.concatenate([ds.p["train"], ds.p["val"]])
            q = np.concatenate([ds.q["train"], ds.q["val"]])
            if len(p) > MAX_FIT_ROWS:  # a fixed subset: families fit in seconds on 10^6-row CSVs
                keep = np.sort(np.random.default_rng(0).choice(len(p), MAX_FIT_ROWS, replace=False))
                p, q = p[keep], q[keep]
            return p * (1000.0 / self.unit_um), q
        key = ("fit", n_per_axis)
        if key not in self.cache:
            gx = np.linspace(self.lo[0], self.hi[0], n_per_axis)
            gy = np.linspace(self.lo[1], self.hi[1], n_per_axis)
            g = np.stack(np.meshgrid(gx, gy, indexing="xy"), -1).reshape(-1, 2)
            pts = np.concatenate([g, ds.p["train"] * (1000.0 / self.unit_um)])
            self.cache[key] = (pts, self.truth(pts))
        return self.cache[key]

    def finish(self, pre_num: np.ndarray, shift: int, offset: np.ndarray | int = 0) -> np.ndarray:
        """Round half up and clamp, as every family's C does: ``offset + ((num + 2^(s-1)) >> s)``
        (arithmetic shift; s = 0 means no rounding), then the DAC clamp."""
        num = np.asarray(pre_num, dtype=np.int64)
        out = (num + (np.int64(1) << (shift - 1))) >> shift if shift > 0 else num.copy()
        out = out + np.asarray(offset, dtype=np.int64)
        if self.code_range is not None:
            out = np.clip(out, *self.code_range)
        return out

    @cached_property
    def parity_box(self) -> tuple[np.ndarray, np.ndarray, tuple[bool, bool]]:
        """(lo, hi, mirror) int64 per axis: where a family tests the IK's parity in each input.

        Symmetry is a property of the IK, not of the field: on an axis whose domain straddles 0,
        an exact (analytic) IK is tested over the symmetric hull [-M, M], M = max(-lo, hi), so an
        asymmetric field of a gimbal still gets its odd/even outputs. ``mirror[a]`` says the box
        is symmetric about 0 on axis a. Where the IK is not finite on the hull (a singularity
        outside the field), and for measured machines, the box is the domain itself."""
        lo, hi = self.lo.copy(), self.hi.copy()
        if self.scn.mechanism.analytic:
            straddle = (lo < 0) & (hi > 0)
            m = np.maximum(-lo, hi)
            blo, bhi = np.where(straddle, -m, lo), np.where(straddle, m, hi)
            probe = np.random.default_rng(5).integers(blo, bhi + 1, (4096, 2))
            probe = np.concatenate([probe, np.stack(np.meshgrid([blo[0], bhi[0]], [blo[1], bhi[1]]), -1).reshape(-1, 2)])
            with np.errstate(all="ignore"):
                try:
                    ok = bool(np.all(np.isfinite(self.truth(probe))))
                except (NnikError, ValueError, ArithmeticError):
                    ok = False
            if ok:
                lo, hi = blo, bhi
        return lo, hi, (bool(lo[0] == -hi[0]), bool(lo[1] == -hi[1]))
