"""The tanh replacements' specifications: the integer contract's constants, the paper's
coefficients, the variant specs (:data:`SPECS`) and the :class:`Variant` a spec is built into
(see :mod:`nnik.implementations.mlp.tanh`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


Q_IN = 12  # input Q3.12
Q_OUT = 15  # output Q15
ONE_OUT = 1 << Q_OUT  # 32768
Y_MAX = ONE_OUT - 1  # 32767, the saturated output
A_MAX = 1 << 15  # |v| ranges over 0..32768

PAPER_RMS = 1.7362e-5  # CBA 2012, 000, after eq. 14

# Coefficients printed in the paper (eq. 10-13), highest power first, in the global
# variable x.  The text extraction lost every minus sign; the signs here are the ones of
# our own least-squares fit, which matches the magnitudes to 3-5 digits.  Segment 4 is
# printed for (3, 5.3] but its coefficients are those of a least-squares fit over [3, 5.5].
# Evaluated as printed, they give RMS 1.7363e-5 over [0, 6] (see paper_report()).
PAPER_PUBLISHED_COEFFS: tuple[tuple[float, ...], ...] = (
    (-1.7172e-2, 1.9120e-1, -4.3475e-1, 2.4715e-2, 9.976e-1, 5.5817e-5),
    (-4.2318e-3, 9.2773e-3, 1.2754e-1, -7.2015e-1, 1.4621, -1.1295e-1),
    (2.8854e-3, -4.4357e-2, 2.8025e-1, -9.1555e-1, 1.5584, -1.1520e-1),
    (1.3575e-4, -3.2404e-3, 3.1089e-2, -1.5018e-1, 3.6627e-1, 6.3795e-1),
)
PAPER_BREAKS = (0.0, 1.0, 2.0, 3.0, 5.3)


# --------------------------------------------------------------------------------------
# specifications
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PolySpec:
    """Piecewise polynomial on |x|.

    Either ``breaks`` (x0 < x1 < ... < xn = saturation; segments [x0,x1], (x1,x2], ...,
    1 beyond xn) or ``shift`` k with ``nseg`` segments [j*2^k, (j+1)*2^k) in Q3.12 units
    (segment index ``|v| >> k``, saturation at nseg*2^k).
    """

    name: str
    description: str
    degree: int | tuple[int, ...]
    method: str  # "lsq" | "minimax"
    breaks: tuple[float, ...] | None = None
    shift: int | None = None
    nseg: int | None = None
    continuous: bool = False
    uniform_q: bool = False  # one Q format per Horner step for all segments (constant shifts)
    tune: bool = False  # integer-aware tuning of the int16 coefficients (minimax variants)
    origin_zero: bool = True  # constrain p(0) = 0 (the paper's fit does not)


@dataclass(frozen=True)
class LerpSpec:
    """Interpolated table.  ``regions`` = ((x_lo, x_hi, k), ...) contiguous from 0; region
    nodes are 2^k Q3.12 units apart; saturation at the last x_hi.  An empty description
    is generated from the regions."""

    name: str
    description: str
    regions: tuple[tuple[float, float, int], ...]
    tune: bool = True


@dataclass
class Variant:
    """One fitted tanh replacement: the float pieces and their integer realisation."""

    name: str
    description: str
    kind: str  # "poly" | "lerp"
    method: str  # "lsq" | "minimax" | "table"
    sat_x: float  # output is 1 (32767) from here on


    sat_a: int  # first |v| that saturates
    nseg: int
    degree: int
    continuous: bool
    # float pieces: (x_lo, x_hi, x0, coeffs ascending in t = x - x0); for a table, one
    # linear piece per node interval (the float nodes are also in float_nodes)
    pieces: list = field(default_factory=list)
    # ---- integer realisation ----
    # poly: segments[j] = dict(a_lo, a_hi, org, s, ...); coef[j] = Horner order c_d..c_0
    #       (int16); q[j] = Q formats of c_d..c_0; sh[j] = shift of each of the d steps
    # lerp: regions[r] = dict(a_lo, a_hi, k, off, fb, drop, ...); table = int16 Q15 nodes
    index_shift: int | None = None
    segments: list = field(default_factory=list)
    coef: np.ndarray | None = None
    q: np.ndarray | None = None
    sh: np.ndarray | None = None
    uniform_shifts: bool = False
    regions: list = field(default_factory=list)
    table: np.ndarray | None = None
    float_nodes: np.ndarray | None = None
    # the polynomial's integer value at v = 0 is not 0 (unconstrained fit): the C returns
    # 0 for v = 0 explicitly, keeping the result odd
    pin_zero: bool = False
    origin_zero: bool = False

    @property
    def mults(self) -> int:
        """Estimated multiplies per call (the cost that matters on AVR/PIC18)."""
        return 1 if self.kind == "lerp" else self.degree

    @property
    def coeff_bytes(self) -> int:
        """Flash bytes of tables/coefficients (code excluded)."""
        if self.kind == "lerp":
            return 2 * int(self.table.size)
        n = 2 * int(self.coef.size)
        if not self.uniform_shifts:
            n += int(self.sh.size)  # uint8 shift table
        return n

    @property
    def cost(self) -> tuple[int, int]:
        return (self.mults, self.coeff_bytes)

    def __repr__(self) -> str:  # keep reprs short (numpy arrays inside)
        return f"Variant({self.name!r}, {self.kind}/{self.method}, nseg={self.nseg}, deg={self.degree})"


def _x_to_a(x: float) -> float:
    return x * (1 << Q_IN)


SPECS: tuple[PolySpec | LerpSpec, ...] = (
    PolySpec(
        "paper_lsq5",
        "paper (CBA 2012 eq. 10-14): [0,1],(1,2],(2,3],(3,5.3], degree 5, least squares",
        5, "lsq", breaks=PAPER_BREAKS, origin_zero=False,
    ),
    PolySpec(
        "paper_minimax5",
        "paper pieces, degree 5, minimax (LP), p(0) = 0, int16 coefficients tuned",
        5, "minimax", breaks=PAPER_BREAKS, tune=True,
    ),
    PolySpec(
        "paper_minimax5_c",
        "paper pieces, degree 5, minimax (LP) continuous at the breakpoints and at 5.3, "
        "p(0) = 0, tuned",
        5, "minimax", breaks=PAPER_BREAKS, continuous=True, tune=True,
    ),
    PolySpec(
        "lsq3_x11",
        "11 segments of 1/2 indexed by |v|>>11, cubic, least squares, p(0) = 0, 1 from 5.5",
        3, "lsq", shift=11, nseg=11, uniform_q=True,
    ),
    PolySpec(
        "minimax3_x11",
        "11 segments of 1/2 indexed by |v|>>11, cubic, minimax, p(0) = 0, tuned, 1 from 5.5",
        3, "minimax", shift=11, nseg=11, uniform_q=True, tune=True,
    ),
    PolySpec(
        "minimax2_x22",
        "22 segments of 1/4 indexed by |v|>>10, quadratic, minimax, tuned, 1 from 5.5",
        2, "minimax", shift=10, nseg=22, uniform_q=True, tune=True,
    ),
    PolySpec(
        "minimax2_x44",
        "44 segments of 1/8 indexed by |v|>>9, quadratic, minimax, tuned, 1 from 5.5",
        2, "minimax", shift=9, nseg=44, uniform_q=True, tune=True,
    ),
    LerpSpec("lerp32", "", ((0.0, 5.5, 7),)),
    LerpSpec("lerp64", "", ((0.0, 5.5, 6),)),
    LerpSpec("lerp_mr", "", ((0.0, 1.5, 6), (1.5, 3.0, 7), (3.0, 5.5, 9))),
    LerpSpec("lerp_mr4", "", ((0.0, 1.0, 6), (1.0, 2.0, 7), (2.0, 3.5, 8), (3.5, 5.5, 10))),
)

# Name of the default variant; a test checks it equals choose_variant(2.0).name.
DEFAULT_VARIANT = "lerp_mr4"
