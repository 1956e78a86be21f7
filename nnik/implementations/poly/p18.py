"""SDCC pic16 path of the `poly` family: the integer program (nnik.implementations.poly.int_model) as
one __asm__ block on a work area in one RAM bank, bit-exact with poly_int.evaluate.

SDCC compiles ``(int32_t)a * b`` to a call of its 32 x 32 multiply and some 32-bit right shifts
wrongly (4.2: by 15 and 17..19), so every product here is four MULWF/MULLW byte products with
the two sign corrections of a signed 16 x 16 multiply, and every shift is a chain of
RLCF/RRCF on the bytes that matter. The clamp stays in C; the DAC clamp too (in C after the
assembly, only when the range analysis cannot rule it out)."""

from __future__ import annotations

from nnik.implementations.c_common import i32

OFF_D, OFF_P, OFF_O, OFF_R, OFF_H = 0, 8, 12, 20, 24
PRODL, PRODH, WREG = "0xFF3", "0xFF4", "0xFE8"
BANK_BYTES = 256


class _Asm:
    def __init__(self, sym: str):
        self.sym = sym
        self.lines: list[str] = []
        self.n = 0

    def at(self, off: int) -> str:
        return f"{self.sym}+{off}"

    def label(self) -> str:
        self.n += 1
        return f"{self.sym}_{self.n}"

    def emit(self, *ins: str) -> None:
        self.lines += ins


def _mul(a: _Asm, A: int, B) -> None:
    """P = A * B: A the offset of an int16 in the work area, B an offset or ("k", int16)."""
    P = OFF_P
    const = isinstance(B, tuple)
    bl = (lambda: f"mullw {B[1] & 0xFF}") if const else (lambda: f"mulwf {a.at(B)}, B")
    bh = (lambda: f"mullw {(B[1] >> 8) & 0xFF}") if const else (lambda: f"mulwf {a.at(B + 1)}, B")
    a.emit(f"movf {a.at(A)}, W, B", bl(), f"movff {PRODL}, {a.at(P)}", f"movff {PRODH}, {a.at(P + 1)}",
           f"movf {a.at(A + 1)}, W, B", bh(), f"movff {PRODL}, {a.at(P + 2)}", f"movff {PRODH}, {a.at(P + 3)}",
           f"movf {a.at(A)}, W, B", bh(),
           f"movf {PRODL}, W, A", f"addwf {a.at(P + 1)}, F, B", f"movf {PRODH}, W, A",
           f"addwfc {a.at(P + 2)}, F, B", f"clrf {WREG}, A", f"addwfc {a.at(P + 3)}, F, B",
           f"movf {a.at(A + 1)}, W, B", bl(),
           f"movf {PRODL}, W, A", f"addwf {a.at(P + 1)}, F, B", f"movf {PRODH}, W, A",
           f"addwfc {a.at(P + 2)}, F, B", f"clrf {WREG}, A", f"addwfc {a.at(P + 3)}, F, B")
    # signed: subtract A << 16 when B < 0, B << 16 when A < 0
    if const:
        if B[1] < 0:
            a.emit(f"movf {a.at(A)}, W, B", f"subwf {a.at(P + 2)}, F, B",
                   f"movf {a.at(A + 1)}, W, B", f"subwfb {a.at(P + 3)}, F, B")
    else:
        lab = a.label()
        a.emit(f"btfss {a.at(B + 1)}, 7, B", f"bra {lab}", f"movf {a.at(A)}, W, B", f"subwf {a.at(P + 2)}, F, B",
               f"movf {a.at(A + 1)}, W, B", f"subwfb {a.at(P + 3)}, F, B", f"{lab}:")
    lab = a.label()
    if const:
        a.emit(f"btfss {a.at(A + 1)}, 7, B", f"bra {lab}", f"movlw {B[1] & 0xFF}", f"subwf {a.at(P + 2)}, F, B",
               f"movlw {(B[1] >> 8) & 0xFF}", f"subwfb {a.at(P + 3)}, F, B", f"{lab}:")
    else:
        a.emit(f"btfss {a.at(A + 1)}, 7, B", f"bra {lab}", f"movf {a.at(B)}, W, B", f"subwf {a.at(P + 2)}, F, B",
               f"movf {a.at(B + 1)}, W, B", f"subwfb {a.at(P + 3)}, F, B", f"{lab}:")


def _add_const(a: _Asm, off: int, n: int, k: int) -> None:
    """bytes off..off+n-1 += k (mod 2^(8n)), from the lowest non-zero byte of k."""
    k &= (1 << (8 * n)) - 1
    if not k:
        return
    lo = 0
    while (k >> (8 * lo)) & 0xFF == 0:
        lo += 1
    for i in range(lo, n):
        a.emit(f"movlw {(k >> (8 * i)) & 0xFF}", f"{'addwf' if i == lo else 'addwfc'} {a.at(off + i)}, F, B")


def work_offsets(prog) -> dict[str, int]:
    """Offset in the work area of every int16 value of the program (inputs, Horner steps)."""
    where = {"u": OFF_D, "v": OFF_D + 4, "rx": OFF_R, "ry": OFF_R + 2}
    for i, st in enumerate(prog.steps):
        where[st.dst] = OFF_H + 2 * i
    return where


def p18_body(impl) -> str | None:
    from nnik.implementations.poly.c import lsb_used

    prog = impl.prog
    used = lsb_used(prog)
    p = impl.problem
    name = p.name
    w = f"{name}_p18w"
    a = _Asm(f"_{w}")
    where = work_offsets(prog)
    nv = len(prog.steps)

    if OFF_H + 2 * nv > BANK_BYTES:
        return None  # the work area must sit in one RAM bank: such a program uses the portable C

    def op(b):
        return where[b] if isinstance(b, str) else ("k", int(b))

    a.emit(f"BANKSEL _{w}")
    for j, m in enumerate(impl.maps):
        D = OFF_D + 4 * j
        if m.k > 8:
            for _ in range(m.k):
                a.emit(f"rlcf {a.at(D + 3)}, W, B", f"rrcf {a.at(D + 3)}, F, B", f"rrcf {a.at(D + 2)}, F, B",
                       f"rrcf {a.at(D + 1)}, F, B", f"rrcf {a.at(D)}, F, B")
        elif m.k > 0:
            for _ in range(m.k):
                a.emit(f"rlcf {a.at(D + 2)}, W, B", f"rrcf {a.at(D + 2)}, F, B", f"rrcf {a.at(D + 1)}, F, B",
                       f"rrcf {a.at(D)}, F, B")
        for _ in range(-m.k):
            a.emit("bcf 0xFD8, 0, A", f"rlcf {a.at(D)}, F, B", f"rlcf {a.at(D + 1)}, F, B")
    P = OFF_P
    for st in prog.steps:
        _mul(a, where[st.a], op(st.b))
        _add_const(a, P, 4, st.K)
        if st.f <= 16:
            for _ in range(16 - st.f):
                a.emit(f"rlcf {a.at(P + 1)}, F, B", f"rlcf {a.at(P + 2)}, F, B", f"rlcf {a.at(P + 3)}, F, B")
        else:
            for _ in range(st.f - 16):
                a.emit(f"rlcf {a.at(P + 3)}, W, B", f"rrcf {a.at(P + 3)}, F, B", f"rrcf {a.at(P + 2)}, F, B")
        if isinstance(st.L, str):
            L = where[st.L]
            a.emit(f"movf {a.at(L)}, W, B", f"addwf {a.at(P + 2)}, F, B",
                   f"movf {a.at(L + 1)}, W, B", f"addwfc {a.at(P + 3)}, F, B")
        elif st.L is not None:
            _add_const(a, P + 2, 2, int(st.L))
        D = where[st.dst]
        a.emit(f"movff {a.at(P + 2)}, {a.at(D)}", f"movff {a.at(P + 3)}, {a.at(D + 1)}")
    c_clamp = []
    for k, o in enumerate(prog.outs):
        O = OFF_O + 4 * k
        c = o.C + (1 << (o.s - 1))
        for i in range(4):
            a.emit(f"movlw {(c >> (8 * i)) & 0xFF}", f"movwf {a.at(O + i)}, B")
        for A, B, t in o.terms:
            _mul(a, where[A], op(B))
            for _ in range(t):
                a.emit(f"rlcf {a.at(P + 3)}, W, B", f"rrcf {a.at(P + 3)}, F, B", f"rrcf {a.at(P + 2)}, F, B",
                       f"rrcf {a.at(P + 1)}, F, B", f"rrcf {a.at(P)}, F, B")
            a.emit(*[x for i in range(4) for x in (f"movf {a.at(P + i)}, W, B",
                                                   f"{'addwf' if i == 0 else 'addwfc'} {a.at(O + i)}, F, B")])
        lo_b, hi_b = prog.bounds[f"out{k}"]
        r_lo, r_hi = (lo_b + (1 << (o.s - 1))) >> o.s, (hi_b + (1 << (o.s - 1))) >> o.s
        if 8 <= o.s and -32768 <= r_lo and r_hi <= 32767:
            for _ in range(o.s - 16):
                a.emit(f"rlcf {a.at(O + 3)}, W, B", f"rrcf {a.at(O + 3)}, F, B", f"rrcf {a.at(O + 2)}, F, B")
            for _ in range(16 - o.s):
                a.emit(f"rlcf {a.at(O + 1)}, F, B", f"rlcf {a.at(O + 2)}, F, B", f"rlcf {a.at(O + 3)}, F, B")
            a.emit(f"movff {a.at(O + 2)}, {a.at(O)}", f"movff {a.at(O + 3)}, {a.at(O + 1)}",
                   f"clrf {a.at(O + 2)}, B", f"btfsc {a.at(O + 1)}, 7, B", f"setf {a.at(O + 2)}, B",
                   f"movff {a.at(O + 2)}, {a.at(O + 3)}")
        else:
            for _ in range(o.s):
                a.emit(f"rlcf {a.at(O + 3)}, W, B", f"rrcf {a.at(O + 3)}, F, B", f"rrcf {a.at(O + 2)}, F, B",
                       f"rrcf {a.at(O + 1)}, F, B", f"rrcf {a.at(O)}, F, B")
        _add_const(a, O, 4, o.offset)
        if p.code_range is not None and (r_lo + o.offset < p.code_range[0] or r_hi + o.offset > p.code_range[1]):
            c_clamp.append(k)
    lines = [
        "/* work area: one struct in one RAM bank (SDCC cannot bind C variables to asm operands) */",
        "static struct {",
        "    int32_t d[2];  /* +0: x - c, y - c; then u, v in their low halves */",
        "    uint8_t p[4];  /* +8: the product */",
        "    int32_t o[2];  /* +12: the outputs */",
        "    int16_t r[2];  /* +20: the bits the input shifts drop */",
        f"    int16_t h[{max(nv, 1)}];  /* +24: the Horner values */",
        f"}} {w};",
        "",
        f"int8_t {name}_ik(const int32_t in_um[{name.upper()}_N_IN], int32_t out[{name.upper()}_N_OUT])",
        "{",
        "    int8_t clamped = 0;",
        "    int32_t x = in_um[0];",
        "    int32_t y = in_um[1];",
        "",
    ]
    lo, hi = p.lo, p.hi
    for j, src in enumerate(("x", "y")):
        lines += [f"    if ({src} < {i32(lo[j])}) {{ {src} = {i32(lo[j])}; clamped = 1; }}",
                  f"    else if ({src} > {i32(hi[j])}) {{ {src} = {i32(hi[j])}; clamped = 1; }}"]
        c = impl.maps[j].c
        lines.append(f"    {w}.d[{j}] = {src} - {i32(c)};" if c else f"    {w}.d[{j}] = {src};")
        if ("rx", "ry")[j] in used:
            lines.append(f"    {w}.r[{j}] = (int16_t)((uint16_t)(uint32_t){w}.d[{j}] & {(1 << impl.maps[j].k) - 1}u);")
    lines.append("    __asm__(")
    lines += [f'        "{x}\\n"' if x.endswith(":") else f'        "\\t{x}\\n"' for x in a.lines]
    lines.append("    );")
    for k in range(2):
        lines.append(f"    out[{k}] = {w}.o[{k}];")
    for k in c_clamp:
        clo, chi = i32(p.code_range[0]), i32(p.code_range[1])
        lines += [f"    if (out[{k}] < {clo}) out[{k}] = {clo};", f"    else if (out[{k}] > {chi}) out[{k}] = {chi};"]
    lines += ["    return clamped;", "}"]
    return "\n".join(lines)
