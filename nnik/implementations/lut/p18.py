"""PIC18 (SDCC pic16) body of the bilinear table: one __asm__ statement on MULWF.

SDCC cannot bind C variables to assembly operands, so the work happens in one static struct in
one RAM bank (BANKSEL once); the clamp uses NNIK_P18_INW and the DAC clamp NNIK_P18_SAT* from
nnik_kernel.h, the rest is written out here. C copies the inputs in and the outputs out.
"""

from __future__ import annotations

OFF = {"v": 0, "fl": 8, "ng": 9, "aw": 10, "fy": 12, "w11": 14, "ix": 16, "a": 17, "e": 21, "d": 25,
       "f": 27, "t": 29, "o": 31, "r": 39}
PRODL, PRODH, TABLAT, TBLPTRL, TBLPTRH, TBLPTRU, STATUS = (
    "0xFF3", "0xFF4", "0xFF5", "0xFF6", "0xFF7", "0xFF8", "0xFD8")


class Asm:
    """Line collector with addresses in the work struct and unique labels."""

    def __init__(self, sym: str):
        self.sym = sym
        self.lines: list[str] = []
        self.n = 0

    def at(self, field: str, k: int = 0) -> str:
        return f"{self.sym}+{OFF[field] + k}"

    def label(self) -> str:
        self.n += 1
        return f"{self.sym}_L{self.n}"

    def __iadd__(self, more):
        self.lines += list(more)
        return self

    def add_const(self, field: str, k: int, nbytes: int = 4) -> None:
        m = int(k) & ((1 << (8 * nbytes)) - 1)
        for i in range(nbytes):
            self.lines += [f"movlw {(m >> (8 * i)) & 0xFF}", f"{'addwf' if i == 0 else 'addwfc'} {self.at(field, i)}, F, B"]

    def negate(self, field: str, nbytes: int) -> None:
        self.lines += [f"comf {self.at(field, i)}, F, B" for i in range(nbytes - 1, 0, -1)]
        self.lines += [f"negf {self.at(field, 0)}, B", "movlw 0"]
        self.lines += [f"addwfc {self.at(field, i)}, F, B" for i in range(1, nbytes)]

    def sign_fill(self, src: str, dst: str) -> None:
        self.lines += [f"clrf {dst}, B", f"btfsc {src}, 7, B", f"setf {dst}, B"]

    def mac(self, u: str, W: int) -> None:
        """A += U * D: U unsigned (W bits), D signed 16 (modulo 2^32)."""
        a = [self.at("a", i) for i in range(4)]
        d = [self.at("d", i) for i in range(2)]
        uu = [self.at(u, i) for i in range(2)]

        def prod(x, y, o, carry):
            self.lines += [f"movf {x}, W, B", f"mulwf {y}, B", f"movf {PRODL}, W, A", f"addwf {a[o]}, F, B",
                           f"movf {PRODH}, W, A", f"addwfc {a[o + 1]}, F, B"]
            if carry:
                self.lines.append("movlw 0")
                self.lines += [f"addwfc {a[i]}, F, B" for i in range(o + 2, 4)]

        prod(uu[0], d[0], 0, True)
        prod(uu[0], d[1], 1, True)
        if W == 16:
            prod(uu[1], d[1], 2, False)
            prod(uu[1], d[0], 1, True)
        skip = self.label()
        self.lines += [f"btfss {d[1]}, 7, B", f"bra {skip}", f"movf {uu[0]}, W, B", f"subwf {a[2]}, F, B"]
        self.lines += [f"movf {uu[1]}, W, B", f"subwfb {a[3]}, F, B"] if W == 16 else ["movlw 0", f"subwfb {a[3]}, F, B"]
        self.lines.append(f"{skip}:")

    def read(self, field: str, nbytes: int, skip: int = 0) -> None:
        for i in range(nbytes):
            self.lines += ["tblrd*+", f"movff {TABLAT}, {self.at(field, i)}"]
        self.lines += ["tblrd*+"] * skip

    def tblptr_add(self, k: int) -> None:
        m = int(k) & 0xFFFFFF
        self.lines += [f"movlw {m & 0xFF}", f"addwf {TBLPTRL}, F, A", f"movlw {(m >> 8) & 0xFF}",
                       f"addwfc {TBLPTRH}, F, A", f"movlw {m >> 16}", f"addwfc {TBLPTRU}, F, A"]

    def sar(self, field: str, s: int) -> None:
        """field (int32) >>= s, arithmetic."""
        q, r = divmod(s, 8)
        b = [self.at(field, i) for i in range(4)]
        for i in range(4 - q):
            if q:
                self.lines.append(f"movff {b[i + q]}, {b[i]}")
        top = 3 - q
        for _ in range(r):
            self.lines += [f"rlcf {b[top]}, W, B", f"rrcf {b[top]}, F, B"]
            self.lines += [f"rrcf {b[i]}, F, B" for i in range(top - 1, -1, -1)]
        for j in range(top + 1, 4):
            self.sign_fill(b[top], b[j])


def _align(asm: Asm, v: int, k: int) -> None:
    b = [asm.at("v", 4 * v + i) for i in range(3)]
    n = 16 - k
    if n >= 8:
        asm += [f"movff {b[1]}, {b[2]}", f"movff {b[0]}, {b[1]}", f"clrf {b[0]}, B"]
        n -= 8
    elif n <= -8:
        asm += [f"movff {b[1]}, {b[0]}", f"movff {b[2]}, {b[1]}", f"clrf {b[2]}, B"]
        n += 8
    for _ in range(max(n, 0)):
        asm += [f"bcf {STATUS}, 0, A", f"rlcf {b[0]}, F, B", f"rlcf {b[1]}, F, B", f"rlcf {b[2]}, F, B"]
    for _ in range(max(-n, 0)):
        asm += [f"bcf {STATUS}, 0, A", f"rrcf {b[2]}, F, B", f"rrcf {b[1]}, F, B", f"rrcf {b[0]}, F, B"]


def table_part(impl, asm: Asm, flipmask, after_clamp=None) -> list[str]:
    """Input stage, weights, pointer and both outputs' table accumulators; returns the list of
    macro invocations (C tokens) the clamp needs, in order, as ('macro', text) / ('asm', line)."""
    p = impl.problem
    tab = impl.table
    g = tab.grid
    W = g.W
    B = tab.bits // 8
    items = [("asm", f"BANKSEL {asm.sym}")]

    def flush():
        nonlocal items
        items += [("asm", ln) for ln in asm.lines]
        asm.lines = []

    for a in range(2):
        lo, hi = int(p.lo[a]), int(p.hi[a])
        items.append(("macro", f'NNIK_P18_INW("{asm.at("v", 4 * a)}", "{asm.at("fl")}", {lo}, {hi - lo}, '
                               f'"{asm.sym}_in{a}")'))
        v = [asm.at("v", 4 * a + i) for i in range(3)]
        if g.fold[a]:
            m = lo & 0xFFFFFF  # t = w + lo = x (signed 24-bit), then |x|
            for i in range(3):
                asm += [f"movlw {(m >> (8 * i)) & 0xFF}", f"{'addwf' if i == 0 else 'addwfc'} {v[i]}, F, B"]
            lab = asm.label()
            asm += [f"btfss {v[2]}, 7, B", f"bra {lab}", f"comf {v[2]}, F, B", f"comf {v[1]}, F, B",
                    f"negf {v[0]}, B", "movlw 0", f"addwfc {v[1]}, F, B", f"addwfc {v[2]}, F, B"]
            if flipmask[a]:
                asm += [f"movlw {flipmask[a]}", f"xorwf {asm.at('ng')}, F, B"]
            asm += [f"{lab}:"]
        if after_clamp is not None:  # t = x - lo, or |x| on a folded axis
            after_clamp(asm, a)
        _align(asm, a, g.k[a])
        if a == 0:
            asm += [f"movff {v[2]}, {asm.at('ix')}"]
            asm += ([f"movff {v[0]}, {asm.at('aw')}", f"movff {v[1]}, {asm.at('aw', 1)}"] if W == 16
                    else [f"movff {v[1]}, {asm.at('aw')}"])
        else:
            asm += ([f"movff {v[0]}, {asm.at('fy')}", f"movff {v[1]}, {asm.at('fy', 1)}"] if W == 16
                    else [f"movff {v[1]}, {asm.at('fy')}"])
        flush()
    # pointers: TBLPTR = output 0's node; r[0..1] = output 1's byte offset when shapes differ
    tsym = f"_{p.name}_tab"
    toff = [k * B for k in table_offsets(tab)]

    def offset(dep):
        if dep == "xy":
            code = [f"movf {asm.at('v', 6)}, W, B", f"mullw {g.n[0]}", f"movf {asm.at('ix')}, W, B",
                    f"addwf {PRODL}, F, A", "movlw 0", f"addwfc {PRODH}, F, A"]
        else:
            code = [f"movff {asm.at('v', 6) if dep == 'y' else asm.at('ix')}, {PRODL}", f"clrf {PRODH}, A"]
        for _ in range(B.bit_length() - 1):
            code += [f"bcf {STATUS}, 0, A", f"rlcf {PRODL}, F, A", f"rlcf {PRODH}, F, A"]
        return code

    asm += offset(tab.dep[0])
    if tab.dep != ("xy", "xy"):
        if tab.dep[1] != tab.dep[0]:
            asm += [f"movff {PRODL}, {asm.at('t')}", f"movff {PRODH}, {asm.at('t', 1)}"] + offset(tab.dep[1])
        asm += [f"movff {PRODL}, {asm.at('r')}", f"movff {PRODH}, {asm.at('r', 1)}"]
        if tab.dep[1] != tab.dep[0]:
            asm += [f"movff {asm.at('t')}, {PRODL}", f"movff {asm.at('t', 1)}, {PRODH}"]
    asm += [f"movlw LOW({tsym} + {toff[0]})", f"addwf {PRODL}, W, A", f"movwf {TBLPTRL}, A",
            f"movlw HIGH({tsym} + {toff[0]})", f"addwfc {PRODH}, W, A", f"movwf {TBLPTRH}, A",
            f"movlw UPPER({tsym} + {toff[0]})", f"movwf {TBLPTRU}, A", "movlw 0", f"addwfc {TBLPTRU}, F, A"]
    # weights
    aw = asm.at
    if W == 16:
        asm += [f"movf {aw('aw', 1)}, W, B", f"mulwf {aw('fy', 1)}, B", f"movff {PRODL}, {aw('w11')}",
                f"movff {PRODH}, {aw('w11', 1)}", f"movf {aw('aw')}, W, B", f"mulwf {aw('fy')}, B",
                f"movff {PRODH}, {aw('t')}"]
        for x, y in (("aw", 1), ("aw", 0)):
            yy = aw("fy", 0) if y == 1 else aw("fy", 1)
            asm += [f"movf {aw(x, y)}, W, B", f"mulwf {yy}, B", f"movf {PRODL}, W, A", f"addwf {aw('t')}, F, B",
                    f"movf {PRODH}, W, A", f"addwfc {aw('w11')}, F, B", "movlw 0", f"addwfc {aw('w11', 1)}, F, B"]
        asm += [f"movf {aw('w11')}, W, B", f"subwf {aw('aw')}, F, B", f"movf {aw('w11', 1)}, W, B",
                f"subwfb {aw('aw', 1)}, F, B"]
    else:
        asm += [f"movf {aw('aw')}, W, B", f"mulwf {aw('fy')}, B", f"movff {PRODH}, {aw('w11')}",
                f"movf {aw('w11')}, W, B", f"subwf {aw('aw')}, F, B"]
    flush()
    return items


def table_offsets(tab) -> list[int]:
    """Entry index where each output's table starts."""
    return [0, tab.stored(0).size]


def output_acc(impl, asm: Asm, o: int, negate_odd: bool = True) -> None:
    tab = impl.table
    g = tab.grid
    W = g.W
    B = tab.bits // 8
    at = asm.at
    skip = B - 2
    if o == 1 and tab.dep == ("xy", "xy"):
        asm.tblptr_add(g.n[0] * g.n[1] * B - (g.n[0] + 2) * B)
    elif o == 1:
        tsym = f"_{impl.problem.name}_tab"
        k1 = table_offsets(tab)[1] * B
        asm += [f"movlw LOW({tsym} + {k1})", f"addwf {at('r')}, W, B", f"movwf {TBLPTRL}, A",
                f"movlw HIGH({tsym} + {k1})", f"addwfc {at('r', 1)}, W, B", f"movwf {TBLPTRH}, A",
                f"movlw UPPER({tsym} + {k1})", f"movwf {TBLPTRU}, A", "movlw 0", f"addwfc {TBLPTRU}, F, A"]
    asm.read("e", B)
    if B == 4:
        asm += [f"clrf {at('a', i)}, B" for i in range(4)]
    elif W == 16:
        asm += [f"clrf {at('a', 0)}, B", f"clrf {at('a', 1)}, B", f"movff {at('e', 0)}, {at('a', 2)}",
                f"movff {at('e', 1)}, {at('a', 3)}"]
    else:
        asm += [f"clrf {at('a', 0)}, B", f"movff {at('e', 0)}, {at('a', 1)}", f"movff {at('e', 1)}, {at('a', 2)}"]
        asm.sign_fill(at("e", 1), at("a", 3))
    asm.read("d", 2, skip)
    asm += [f"movf {at('e', 0)}, W, B", f"subwf {at('d', 0)}, F, B", f"movf {at('e', 1)}, W, B",
            f"subwfb {at('d', 1)}, F, B"]
    if tab.dep[o] == "y":
        asm.mac("fy", W)
        return combine(impl, asm, o, negate_odd)
    if tab.dep[o] == "x":  # fx = a + w11 into the scratch t
        asm += [f"movf {at('aw')}, W, B", f"addwf {at('w11')}, W, B", f"movwf {at('t')}, B"]
        if W == 16:
            asm += [f"movf {at('aw', 1)}, W, B", f"addwfc {at('w11', 1)}, W, B", f"movwf {at('t', 1)}, B"]
        asm.mac("t", W)
        return combine(impl, asm, o, negate_odd)
    asm.mac("aw", W)
    asm.tblptr_add(g.n[0] * B - 2 * B)
    asm.read("f", 2, skip)
    asm += [f"movf {at('e', 0)}, W, B", f"subwf {at('f', 0)}, W, B", f"movwf {at('d', 0)}, B",
            f"movf {at('e', 1)}, W, B", f"subwfb {at('f', 1)}, W, B", f"movwf {at('d', 1)}, B"]
    asm.mac("fy", W)
    asm.read("d", 2, skip)
    asm += [f"movf {at('f', 0)}, W, B", f"subwf {at('d', 0)}, F, B", f"movf {at('f', 1)}, W, B",
            f"subwfb {at('d', 1)}, F, B"]
    asm.mac("w11", W)
    combine(impl, asm, o, negate_odd)


def combine(impl, asm: Asm, o: int, negate_odd: bool = True) -> None:
    """int32 entries: acc = e00 + (S >> W); then the odd output's negation (if negate_odd)."""
    tab = impl.table
    W = tab.grid.W
    B = tab.bits // 8
    at = asm.at
    if B == 4:  # acc = e00 + (S >> W)
        q = W // 8
        asm.sign_fill(at("a", 3), at("t"))
        srcs = [at("a", q + i) for i in range(4 - q)] + [at("t")] * q
        for i in range(4):
            asm += [f"movf {srcs[i]}, W, B", f"{'addwf' if i == 0 else 'addwfc'} {at('e', i)}, F, B"]
        asm += [f"movff {at('e', i)}, {at('a', i)}" for i in range(4)]
    if negate_odd:
        odd_negation(impl, asm, o)


def odd_negation(impl, asm: Asm, o: int) -> None:
    """a = -a where output o is odd in a folded axis whose input was negative."""
    if impl.table.odd[o].any():
        lab = asm.label()
        asm += [f"btfss {asm.at('ng')}, {o}, B", f"bra {lab}"]
        asm.negate("a", 4)
        asm += [f"{lab}:"]


def finish(impl, asm: Asm, o: int, items: list) -> None:
    fin = impl.final_stage()
    s, off = fin["final_shift"][o], fin["final_off_int"][o]
    if s > 0:
        asm.add_const("a", 1 << (s - 1))
        asm.sar("a", s)
    if off:
        asm.add_const("a", off)
    items += [("asm", ln) for ln in asm.lines]
    asm.lines = []
    cr = impl.problem.code_range
    if cr is not None:
        lo, hi = (int(v) for v in cr)
        items.append(("macro", f'NNIK_P18_SATGE("{asm.at("a")}", {hi + 1}, {hi}, "{asm.sym}_cg{o}")'))
        items.append(("macro", f'NNIK_P18_SATLT("{asm.at("a")}", {lo}, {lo}, "{asm.sym}_cl{o}")'))
    items += [("asm", f"movff {asm.at('a', i)}, {asm.at('o', 4 * o + i)}") for i in range(4)]


def render(impl, items: list, w: str, extra_fields: str = "") -> str:
    name = impl.problem.name
    NAME = name.upper()
    text = []
    for kind, s in items:
        text.append(f"        {s}" if kind == "macro" else f'        "{s}\\n"')
    lines = [
        "/* work area of the PIC18 assembly: one struct, one RAM bank */",
        "static struct {",
        "    int32_t v[2];   /* +0: inputs, then t */",
        "    int8_t fl;      /* +8: an input was clamped */",
        "    uint8_t ng;     /* +9: bit o: negate output o */",
        "    uint8_t aw[2];  /* +10: a = fx - w11 */",
        "    uint8_t fy[2];  /* +12 */",
        "    uint8_t w11[2]; /* +14 */",
        "    uint8_t ix;     /* +16 */",
        "    uint8_t a[4];   /* +17: accumulator */",
        "    uint8_t e[4];   /* +21: e00 */",
        "    uint8_t d[2];   /* +25: difference */",
        "    uint8_t f[2];   /* +27: e01 */",
        "    uint8_t t[2];   /* +29: scratch */",
        "    int32_t o[2];   /* +31: outputs */",
        f"    uint8_t r[8];   /* +39: base scratch */{extra_fields}",
        f"}} {w};",
        "",
        f"int8_t {name}_ik(const int32_t in_um[{NAME}_N_IN], int32_t out[{NAME}_N_OUT])",
        "{",
        f"    {w}.v[0] = in_um[0];",
        f"    {w}.v[1] = in_um[1];",
        f"    {w}.fl = 0;",
        f"    {w}.ng = 0;",
        "    __asm__(",
        *text,
        "    );",
        f"    out[0] = {w}.o[0];",
        f"    out[1] = {w}.o[1];",
        f"    return {w}.fl;",
        "}",
    ]
    return "\n".join(lines)


def body(impl, ctx, base_hook=None, after_clamp=None) -> str:
    """The PIC18 function (work struct + function), see :func:`items`."""
    return render(impl, items(impl, ctx, base_hook, after_clamp), f"{impl.problem.name}_p18")


def items(impl, ctx, base_hook=None, after_clamp=None) -> list:
    """(kind, text) items of the __asm__ statement: ("asm", line) or ("macro", invocation).
    base_hook(asm, o) appends assembly that turns the table accumulator A of output o into the
    total before rounding."""
    w = f"{impl.problem.name}_p18"
    asm = Asm(f"_{w}")
    items = table_part(impl, asm, ctx["flipmask"], after_clamp)
    for o in range(2):
        output_acc(impl, asm, o, negate_odd=base_hook is None)
        if base_hook is not None:  # the base first, then base + residual negated together
            base_hook(asm, o)
            odd_negation(impl, asm, o)
        finish(impl, asm, o, items)
    return items
