"""The `poly` family's integer program: Horner's scheme as a straight list of int16 steps, the
exponents chosen by range analysis, a proof by interval arithmetic that nothing overflows, and
the numpy model the C matches bit for bit.

A step is ``dst = ((a * b + K) >> f) + L`` with ``a``, ``b`` int16 values (``b`` may be an int16
constant), the exact int32 product, an int32 constant ``K`` (rounding half, and in 32-bit
coefficient mode the coefficient itself), an arithmetic shift ``f`` and ``L`` an int16 constant
or an earlier value; ``dst`` is an int16. Each value ``n`` stands for ``n * 2^-e`` (``e`` its
exponent); the inputs ``u``, ``v`` have ``e = 15`` (``t = u / 2^15``). An output is
``num = C + sum_k ((A_k * B_k) >> t_k)`` in int32 and ``pre = num / 2^s + offset``.

``width = 32`` (the wide path, nnik.implementations.poly.wide) is the same program one size up:
int32 values and constants, exact int64 products, shifts up to 63, the inputs unshifted
(``e = 15 + k``); the output sums stay int32.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nnik.errors import NnikError

I16 = 32767


def vmax(width: int) -> int:
    """The largest value of a step's result: int16 or int32."""
    return (1 << (width - 1)) - 1


def fmax(width: int) -> int:
    """The largest shift of a product (int32 or int64)."""
    return 2 * width - 1
MARGIN = 1.0 / 64  # headroom over the sampled range (the interval proof is the real check)
SLACK = 8  # int16 units for the rounding errors that accumulate in a chain
F_MAX = 31
BOXES = 64  # per axis, for the interval proof


class Node:
    """A real-valued node of the Horner DAG: value = a * b + add."""

    _n = 0

    def __init__(self, kind: str, a=None, b=None, add=None, name: str | None = None):
        self.kind, self.a, self.b, self.add = kind, a, b, add
        if name is None:
            Node._n += 1
            name = f"n{Node._n}"
        self.name = name

    def value(self, env: dict) -> np.ndarray:
        if self.name in env:
            return env[self.name]
        b = self.b.value(env) if isinstance(self.b, Node) else self.b
        v = self.a.value(env) * b
        if isinstance(self.add, Node):
            v = v + self.add.value(env)
        elif self.add is not None:
            v = v + self.add
        env[self.name] = v
        return v


def mac(a, b, add=None) -> Node | float:
    """a * b + add with a or b a Node (a const operand goes to b)."""
    if not isinstance(a, Node):
        a, b = b, a
    if add is not None and not isinstance(add, Node) and add == 0.0:
        add = None
    return Node("mac", a, b, add)


def horner1(cn: dict, y) -> Node | float | None:
    """sum_n cn[n] y^n by Horner; a float if only the constant."""
    if not cn:
        return None
    top = max(cn)
    h = cn.get(top, 0.0)
    for n in range(top - 1, -1, -1):
        h = mac(h, y, cn.get(n))
    return h


def horner2(cmn: dict, x, y) -> Node | float | None:
    """sum c[m, n] x^m y^n = sum_m x^m Q_m(y), outer Horner in x."""
    if not cmn:
        return None
    top = max(m for m, _ in cmn)
    q = [horner1({n: c for (mm, n), c in cmn.items() if mm == m}, y) for m in range(top + 1)]
    h = q[top]
    for m in range(top - 1, -1, -1):
        h = mac(h, x, q[m])
    return h


@dataclass
class OutputPlan:
    """One output: num = C + sum (A * B) >> t, the constant term c00 and the structure."""

    terms: list  # [(A Node, B Node | float)]
    c00: float
    shape: str  # e.g. "u * H(u^2, v^2)"


def const_exp(c: float, cap: int = 40, width: int = 16) -> int:
    """The finest exponent e with |round(c 2^e)| <= 32767 (2^31 - 1 for width 32)."""
    lim = vmax(width)
    if c == 0:
        return cap
    e = min(cap, math.floor(math.log2(lim / abs(c))))
    while abs(round(c * 2.0**e)) > lim:
        e -= 1
    return e


def qconst(c: float) -> float:
    e = const_exp(c)
    return round(c * 2.0**e) / 2.0**e


def plan_output(coefs: dict, c00: float, shared: dict, split: bool, grid_env: dict) -> OutputPlan:
    """Factor the polynomial by the parities of its terms and lay out its Horner DAG."""
    def parity(idx):
        ps = {ij[idx] % 2 for ij in coefs}
        zero = all(ij[idx] == 0 for ij in coefs)
        return ps, zero

    (px, zx), (py, zy) = parity(0), parity(1)
    ax = 1 if px == {1} else 0
    ay = 1 if py == {1} else 0
    sx = 2 if len(px) == 1 and not zx else 1
    sy = 2 if len(py) == 1 and not zy else 1
    X = shared["u2"] if sx == 2 else shared["u"]
    Y = shared["v2"] if sy == 2 else shared["v"]
    cmn = {((i - ax) // sx, (j - ay) // sy): c for (i, j), c in coefs.items() if c != 0.0}
    xs = "u^2" if sx == 2 else "u"
    ys = "v^2" if sy == 2 else "v"

    def term(a_node, cdict, build) -> list:
        """[(a_node, H)] with H built from cdict, or split: [(a_node, C1), (a_node, G)]."""
        h = build(cdict)
        if h is None:
            return []
        if not (isinstance(h, Node) and split):
            return [(a_node, h)]
        hv = h.value(dict(grid_env))
        c1 = qconst(0.5 * (hv.max() + hv.min()))
        c2 = dict(cdict)
        k0 = (0, 0) if isinstance(next(iter(cdict)), tuple) else 0
        c2[k0] = c2.get(k0, 0.0) - c1
        g = build(c2)
        return ([(a_node, c1)] if c1 != 0.0 else []) + [(a_node, g)]

    def b2(c):
        return horner2(c, X, Y)

    def b1(c):
        return horner1(c, Y)

    if ax or ay:
        p = {(1, 0): shared["u"], (0, 1): shared["v"], (1, 1): shared["uv"]}[(ax, ay)]
        pname = {(1, 0): "u", (0, 1): "v", (1, 1): "uv"}[(ax, ay)]
        return OutputPlan(term(p, cmn, b2), c00, f"{pname} * H({xs}, {ys})" + (" split" if split else ""))
    terms = term(X, {(m - 1, n): c for (m, n), c in cmn.items() if m >= 1}, b2)
    terms += term(Y, {n - 1: c for (m, n), c in cmn.items() if m == 0 and n >= 1}, b1)
    return OutputPlan(terms, c00, f"{xs} * HX + {ys} * HY" + (" split" if split else ""))


def split_constants(terms: list, env: dict, tol: float) -> list:
    """A final product by a constant whose int16 rounding errs more than `tol` (output units)
    over the domain becomes two products: the int16 constant and its finer remainder."""
    out = []
    for A, B in terms:
        if isinstance(B, Node):
            out.append((A, B))
            continue
        hi = qconst(B)
        lo = B - hi
        amax = float(np.abs(A.value(dict(env))).max())
        out.append((A, hi))
        if lo != 0.0 and amax * abs(lo) > tol:
            out.append((A, lo))
    return out


# ---- the integer program --------------------------------------------------------------------------

@dataclass
class Step:
    dst: str
    a: str
    b: str | int  # value name or int16 constant
    K: int
    f: int
    L: str | int | None  # value name, int16 constant, or None


@dataclass
class OutInt:
    C: int
    terms: list  # [(A name, B name | int const, t)]
    s: int
    offset: int


@dataclass
class Program:
    steps: list = field(default_factory=list)
    outs: list = field(default_factory=list)
    exps: dict = field(default_factory=dict)
    bounds: dict = field(default_factory=dict)  # name -> proven (lo, hi) over the domain

    @property
    def n_mul(self) -> int:
        return len(self.steps) + sum(len(o.terms) for o in self.outs)


def _emax(m: float, guard: int, width: int = 16) -> int:
    lim = vmax(width) * 2.0 ** (-guard) / (1 + MARGIN) - SLACK
    if m <= 0:
        return 40
    return math.floor(math.log2(lim / m))


def _topo(plans: list[OutputPlan]) -> list[Node]:
    order, seen = [], set()

    def visit(n):
        if not isinstance(n, Node) or n.name in seen or n.kind != "mac":
            return
        seen.add(n.name)
        visit(n.a)
        visit(n.b)
        visit(n.add)
        order.append(n)
    for p in plans:
        for a, b in p.terms:
            visit(a)
            visit(b)
    return order


def build_program(plans: list[OutputPlan], grid_env: dict, coef_bits: int, guard: int,
                  urange: list[tuple[int, int]], lower: dict | None = None, trim: int = 0,
                  rounding: bool = True, width: int = 16) -> Program:
    """Exponents from the sampled real ranges (minus `lower` extra bits per node), then the
    integer steps. `trim`: a constant multiplier may give up to this many bits so that its step
    shifts by 16 (free on an 8-bit MCU); `rounding`: round half up in each step (else floor);
    `width`: 16, or 32 for the wide path (grid_env's e_u, e_v: the inputs' exponents)."""
    F_MAX = fmax(width)  # noqa: N806 - the module's 16-bit constant, per width
    cap_e = 40 if width == 16 else 72
    def cexp(c):
        return const_exp(c, cap_e, width)

    lower = lower or {}
    env = dict(grid_env)
    nodes = _topo(plans)
    cap: dict = {}
    for _ in range(4 * len(nodes) + 4):
        exps = {"u": grid_env.get("e_u", 15), "v": grid_env.get("e_v", 15), "rx": grid_env.get("e_rx", 15), "ry": grid_env.get("e_ry", 15)}
        for n in nodes:
            val = n.value(env)
            ea = exps[n.a.name]
            if isinstance(n.b, Node):
                eb = exps[n.b.name]
                prod = n.a.value(env) * n.b.value(env)
            else:
                eb = cexp(n.b)
                prod = n.a.value(env) * n.b
            e = min(_emax(np.abs(val).max(), guard, width), cap.get(n.name, 99))
            if isinstance(n.add, Node):
                e = min(e, exps[n.add.name], _emax(np.abs(prod).max(), guard, width))
            elif n.add is not None:
                e = min(e, _emax(abs(n.add), guard, width))  # 32-bit mode falls back to L when K is too wide
            e = min(e, ea + eb) - lower.get(n.name, 0)
            if isinstance(n.add, Node):
                exps[n.add.name] = e  # lowering an earlier value's exponent is always safe
            exps[n.name] = e
        # a shift of more than F_MAX: make the operand coarser and go again
        again = False
        for n in nodes:
            if isinstance(n.b, Node):
                f = exps[n.a.name] + exps[n.b.name] - exps[n.name]
                if f > F_MAX:
                    for opnd, other in ((n.a, n.b), (n.b, n.a)):
                        if opnd.kind == "mac":
                            cap[opnd.name] = exps[n.name] + F_MAX - exps[other.name]
                            again = True
                            break
        if not again:
            break
    prog = Program(exps=exps)
    for n in nodes:
        e, ea = exps[n.name], exps[n.a.name]
        if isinstance(n.b, Node):
            eb, b = exps[n.b.name], n.b.name
        else:
            eb = min(cexp(n.b), e + F_MAX - ea)
            if width < ea + eb - e <= width + trim:
                eb = e + width - ea
            b = int(round(n.b * 2.0**eb))
            if b == 0:
                raise NnikError(f"poly: coefficient {n.b:g} vanishes at 2^-{eb}")
        f = ea + eb - e
        if not 0 <= f <= F_MAX:
            raise NnikError(f"poly: shift {f} of {n.name} outside [0, {F_MAX}]")
        half = (1 << (f - 1)) if f > 0 and rounding else 0
        if isinstance(n.add, Node):
            K, L = half, n.add.name
            if exps[n.add.name] != e:
                raise NnikError(f"poly: {n.add.name} is not aligned with {n.name}")
        elif n.add is None:
            K, L = half, None
        elif coef_bits == 32 and abs(n.add) * 2.0 ** (ea + eb) < 2.0 ** (2 * width - 3):
            K, L = int(round(n.add * 2.0 ** (ea + eb))) + half, None
        else:
            K, L = half, int(round(n.add * 2.0**e))
        prog.steps.append(Step(n.name, n.a.name, b, K, f, L))
    for p in plans:
        et = []
        for A, B in p.terms:
            eb = exps[B.name] if isinstance(B, Node) else cexp(B)
            et.append(exps[A.name] + eb)
        tot = sum(A.value(env) * (B.value(env) if isinstance(B, Node) else B) for A, B in p.terms) \
            if p.terms else np.zeros(1)
        offset = int(round(p.c00))
        rng = np.abs(tot + (p.c00 - offset)).max() * (1 + MARGIN) + 1.0
        s = min(et + [math.floor(math.log2(2.0**30 / rng))])
        if s < 1:
            raise NnikError("poly: output range does not fit int32")
        terms = []
        for (A, B), e_ in zip(p.terms, et):
            b = B.name if isinstance(B, Node) else int(round(B * 2.0 ** cexp(B)))
            terms.append((A.name, b, e_ - s))
        prog.outs.append(OutInt(int(round((p.c00 - offset) * 2.0**s)), terms, s, offset))
    return prog


MAX_LOWER = 12  # rounds of "lower the failing value's exponent" before giving up


def build_proven(plans: list[OutputPlan], env: dict, config: dict, urange: list[tuple[int, int]],
                 rmax: tuple[int, int], describe, width: int = 16) -> Program:
    """build_program, then prove; a value the proof fails gets its exponent lowered by one bit
    and the program is built again (MAX_LOWER rounds; with a ``guard`` the first must hold)."""
    guard = config.get("guard")
    lower: dict = {}
    for _ in range(MAX_LOWER + 1):
        prog = build_program(plans, env, config["coef_bits"], guard or 0, urange, lower,
                             trim=config["trim"], rounding=config["rounding"], width=width)
        bad = prove(prog, urange, rmax, width)
        if bad is None:
            return prog
        if guard is not None or bad.startswith("out"):
            break
        lower[bad] = lower.get(bad, 0) + 1
    raise NnikError(f"poly: range analysis cannot prove {bad} within int{width}/int{2 * width} ({describe()})")


# ---- interval proof ----------------------------------------------------------------------------

def _box_edges(lo: int, hi: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    cut = np.unique(np.rint(np.linspace(lo, hi + 1, n + 1)).astype(np.int64))
    return cut[:-1], cut[1:] - 1


def _imul(alo, ahi, blo, bhi, same: bool):
    if same:
        sq = np.maximum(alo * alo, ahi * ahi)
        low = np.where((alo <= 0) & (ahi >= 0), 0, np.minimum(alo * alo, ahi * ahi))
        return low, sq
    c = np.stack([alo * blo, alo * bhi, ahi * blo, ahi * bhi])
    return c.min(0), c.max(0)


def prove(prog: Program, urange: list[tuple[int, int]], rmax: tuple[int, int] = (0, 0), width: int = 16) -> str | None:
    """Interval arithmetic over BOXES x BOXES boxes of (u, v): every value in int16, every
    product + K and every partial output sum in int32. Returns the first failing value's name,
    or None; fills prog.bounds."""
    vm, pm = vmax(width), vmax(2 * width)
    ulo, uhi = _box_edges(*urange[0], BOXES)
    if width > 16:  # int64 products + K: exact in Python integers
        ulo, uhi = ulo.astype(object), uhi.astype(object)
    vlo, vhi = _box_edges(*urange[1], BOXES)
    if width > 16:
        vlo, vhi = vlo.astype(object), vhi.astype(object)
    iv = {"u": (ulo[:, None] + 0 * vlo[None, :], uhi[:, None] + 0 * vhi[None, :]),
          "v": (0 * ulo[:, None] + vlo[None, :], 0 * uhi[:, None] + vhi[None, :]),
          "rx": (np.int64(0), np.int64(rmax[0])), "ry": (np.int64(0), np.int64(rmax[1]))}
    i32lo, i32hi = -(2**31), 2**31 - 1

    def get(b):
        if isinstance(b, str):
            return iv[b]
        return np.int64(b), np.int64(b)

    for st in prog.steps:
        alo, ahi = iv[st.a]
        blo, bhi = get(st.b)
        plo, phi = _imul(alo, ahi, blo, bhi, st.a == st.b)
        plo, phi = plo + st.K, phi + st.K
        if plo.min() < -pm - 1 or phi.max() > pm:
            return st.dst
        rlo, rhi = plo >> st.f, phi >> st.f
        if width > 16 and (rlo.min() < -vm - 1 or rhi.max() > vm):  # the C adds L to an int32
            return st.dst
        if st.L is not None:
            llo, lhi = get(st.L)
            rlo, rhi = rlo + llo, rhi + lhi
        if rlo.min() < -vm - 1 or rhi.max() > vm:
            return st.dst
        iv[st.dst] = (rlo, rhi)
        prog.bounds[st.dst] = (int(rlo.min()), int(rhi.max()))
    for k, o in enumerate(prog.outs):
        slo = shi = np.int64(o.C)
        for A, B, t in o.terms:
            alo, ahi = iv[A]
            blo, bhi = get(B)
            plo, phi = _imul(alo, ahi, blo, bhi, A == B)
            slo, shi = slo + (plo >> t), shi + (phi >> t)
            if np.min(slo) < i32lo or np.max(shi) > i32hi:
                return f"out{k}"
        if np.max(shi) + (1 << (o.s - 1)) > i32hi:
            return f"out{k}"
        prog.bounds[f"out{k}"] = (int(np.min(slo)), int(np.max(shi)))
    return None


# ---- the numpy model ---------------------------------------------------------------------------

def step_values(prog: Program, u: np.ndarray, v: np.ndarray, rx: np.ndarray, ry: np.ndarray,
                width: int = 16) -> dict[str, np.ndarray]:
    """Every value of the program (inputs and Horner steps) by name, checking every range."""
    vm = vmax(width)
    vals = {"u": u.astype(np.int64), "v": v.astype(np.int64), "rx": rx.astype(np.int64), "ry": ry.astype(np.int64)}

    def get(b):
        return vals[b] if isinstance(b, str) else np.int64(b)

    for st in prog.steps:
        p = vals[st.a] * get(st.b) + np.int64(st.K)
        if width == 16 and p.size and (p.min() < -(2**31) or p.max() >= 2**31):
            raise NnikError(f"poly: int32 overflow in {st.dst}")
        r = (p >> st.f) + (get(st.L) if st.L is not None else 0)
        if r.size and (r.min() < -vm - 1 or r.max() > vm):
            raise NnikError(f"poly: int{width} overflow in {st.dst}")
        vals[st.dst] = r
    return vals


def evaluate(prog: Program, u: np.ndarray, v: np.ndarray, rx: np.ndarray, ry: np.ndarray,
             width: int = 16) -> np.ndarray:
    """(N,) int64 u, v (and the dropped bits rx, ry) -> (N, 2) int64 num, checking every range.
    Width 32: |a|, |b| < 2^31, so a * b is exact in int64, and prove() bounds a * b + K within it."""
    vals = step_values(prog, u, v, rx, ry, width)

    def get(b):
        return vals[b] if isinstance(b, str) else np.int64(b)

    nums = []
    for o in prog.outs:
        n = np.full(u.shape, o.C, dtype=np.int64)
        for A, B, t in o.terms:
            n = n + ((vals[A] * get(B)) >> t)
            if n.size and (n.min() < -(2**31) or n.max() >= 2**31):
                raise NnikError("poly: int32 overflow in an output sum")
        nums.append(n)
    return np.stack(nums, 1)
