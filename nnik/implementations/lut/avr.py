"""AVR (avr-gcc) body of the bilinear table: one asm statement on the hardware multiplier.

Registers (gcc saves the call-saved ones listed as clobbered):
    r18-r21 A accumulator (also the input stage)   r22:r23 U weight copy (MULSU needs r16-r23)
    r16:r17 D difference   r24:r25 F e01   r14:r15 E e00 (r10:r11 its high word, int32)
    r2:r3 a = fx - w11   r4:r5 fy   r6:r7 w11 (ix before)   r8 zero   r9 flip bits
    Z in_um, then the table   X out   T: an input was clamped
Cycle counts in the comments are for the straight-line path.
"""

from __future__ import annotations

import re

A = ("r18", "r19", "r20", "r21")
U = ("r22", "r23")
D = ("r16", "r17")
F = ("r24", "r25")
E = ("r14", "r15", "r10", "r11")
AW, FY, W11 = ("r2", "r3"), ("r4", "r5"), ("r6", "r7")
ZERO, NEG = "r8", "r9"
PAIR_OPS = ("movw", "adiw", "sbiw")  # rN names rN+1:rN


def _macsu(W: int, u) -> list[str]:
    """A += U * D, U unsigned (W bits), D signed 16 (modulo 2^32)."""
    z = ZERO
    load = [] if u is None else [f"mov {U[0]}, {u[0]}"] if W == 8 else [f"movw {U[0]}, {u[0]}"]
    if W == 8:
        return load + [
                f"mul {D[0]}, {U[0]}", f"add {A[0]}, r0", f"adc {A[1]}, r1", f"adc {A[2]}, {z}", f"adc {A[3]}, {z}",
                f"mulsu {D[1]}, {U[0]}", f"sbc {A[3]}, {z}", f"add {A[1]}, r0", f"adc {A[2]}, r1", f"adc {A[3]}, {z}"]
    return load + [
            f"mul {U[0]}, {D[0]}", f"add {A[0]}, r0", f"adc {A[1]}, r1", f"adc {A[2]}, {z}", f"adc {A[3]}, {z}",
            f"mul {U[1]}, {D[0]}", f"add {A[1]}, r0", f"adc {A[2]}, r1", f"adc {A[3]}, {z}",
            f"mulsu {D[1]}, {U[0]}", f"sbc {A[3]}, {z}", f"add {A[1]}, r0", f"adc {A[2]}, r1", f"adc {A[3]}, {z}",
            f"mulsu {D[1]}, {U[1]}", f"add {A[2]}, r0", f"adc {A[3]}, r1"]


def add_const(regs, k: int) -> list[str]:
    """regs (upper registers, low byte first) += k, modulo 2^(8 len)."""
    m = (-int(k)) & ((1 << (8 * len(regs))) - 1)
    ops = ["lo8", "hi8", "hlo8", "hhi8"]
    return [f"{'subi' if i == 0 else 'sbci'} {r}, {ops[i]}({m})" for i, r in enumerate(regs)]


def negate(regs) -> list[str]:
    regs = list(regs)
    return ([f"com {r}" for r in reversed(regs[1:])] + [f"neg {regs[0]}"]
            + [f"sbci {r}, 0xFF" for r in regs[1:]])


def sar_to(regs, s: int, tmp: str) -> list[str]:
    """regs (4 bytes, int32) = regs >> s (arithmetic)."""
    q, r = divmod(s, 8)
    code = [f"mov {regs[i]}, {regs[i + q]}" for i in range(4 - q)] if q else []
    top = 3 - q
    for _ in range(r):
        code += [f"asr {regs[top]}"] + [f"ror {regs[i]}" for i in range(top - 1, -1, -1)]
    if q:
        code += [f"mov {tmp}, {regs[top]}", f"lsl {tmp}", f"sbc {tmp}, {tmp}"]
        code += [f"mov {regs[j]}, {tmp}" for j in range(top + 1, 4)]
    return code


def _align(k: int) -> list[str]:
    """r20:r19:r18 = t -> t * 2^(16 - k): i in r20, the Q16 fraction in r19:r18."""
    a0, a1, a2 = A[:3]
    n = 16 - k
    code = []
    if n >= 8:
        code += [f"mov {a2}, {a1}", f"mov {a1}, {a0}", f"clr {a0}"]
        n -= 8
    elif n <= -8:
        code += [f"mov {a0}, {a1}", f"mov {a1}, {a2}", f"clr {a2}"]
        n += 8
    for _ in range(max(n, 0)):
        code += [f"lsl {a0}", f"rol {a1}", f"rol {a2}"]
    for _ in range(max(-n, 0)):
        code += [f"lsr {a2}", f"ror {a1}", f"ror {a0}"]
    return code


def input_stage(impl, flipmask, after_clamp=None) -> list[str]:
    """Both inputs: clamp (T flag), fold, align; leaves ix in r6, fx in r2(:r3), iy in r20,
    fy in r4(:r5). after_clamp(a) -> lines run with the table's coordinate t (x - lo, or |x| on
    a folded axis; unsigned 24-bit) in r20:r19:r18."""
    p = impl.problem
    g = impl.table.grid
    code = ["clr " + ZERO, "clt"] + (["clr " + NEG] if any(flipmask) else [])
    for a in range(2):
        lo, hi = int(p.lo[a]), int(p.hi[a])
        code.append(f"nnik_inw {', '.join(A)}, {lo}, {hi - lo}, {U[0]}")
        if g.fold[a]:
            code += add_const(A[:3], lo)  # t = w + lo = x (signed 24-bit)
            code += ["brpl 1f"] + negate(A[:3])
            if flipmask[a]:
                code += [f"ldi {U[0]}, {flipmask[a]}", f"eor {NEG}, {U[0]}"]
            code.append("1:")
        elif g.origin[a] != lo:
            raise AssertionError("unfolded axis starts at lo")
        if after_clamp is not None:
            code += after_clamp(a)
        code += _align(g.k[a])
        if a == 0:
            code += [f"mov {W11[0]}, {A[2]}"]
            code += [f"movw {AW[0]}, {A[0]}"] if g.W == 16 else [f"mov {AW[0]}, {A[1]}"]
        else:
            code += [f"movw {FY[0]}, {A[0]}"] if g.W == 16 else [f"mov {FY[0]}, {A[1]}"]
    return code


def weights(W: int) -> list[str]:
    """w11 = (fx fy) >> W, a = fx - w11."""
    if W == 8:
        return [f"mul {AW[0]}, {FY[0]}", f"mov {W11[0]}, r1", f"sub {AW[0]}, {W11[0]}"]
    return [f"mul {AW[1]}, {FY[1]}", f"movw {W11[0]}, r0",
            f"mul {AW[0]}, {FY[0]}", f"mov {U[0]}, r1",
            f"mul {AW[1]}, {FY[0]}", f"add {U[0]}, r0", f"adc {W11[0]}, r1", f"adc {W11[1]}, {ZERO}",
            f"mul {AW[0]}, {FY[1]}", f"add {U[0]}, r0", f"adc {W11[0]}, r1", f"adc {W11[1]}, {ZERO}",
            f"sub {AW[0]}, {W11[0]}", f"sbc {AW[1]}, {W11[1]}"]


def _offset(tab, dep: str) -> list[str]:
    """r1:r0 = byte offset of output's node: (iy NX + ix), iy or ix, times the entry size."""
    B = tab.bits // 8
    if dep == "xy":
        code = [f"ldi {U[0]}, {tab.grid.n[0]}", f"mul {A[2]}, {U[0]}", f"add r0, {W11[0]}", f"adc r1, {ZERO}"]
    else:
        code = [f"mov r0, {A[2] if dep == 'y' else W11[0]}", "clr r1"]
    return code + ["lsl r0", "rol r1"] * (B.bit_length() - 1)


P1 = ("r12", "r13")  # output 1's node offset when the outputs' tables differ in shape


def pointer(tab, toff) -> list[str]:
    """Z = output 0's node (ix in r6, iy in r20); r13:r12 = output 1's offset if needed."""
    B = tab.bits // 8
    code = _offset(tab, tab.dep[0])
    if tab.dep != ("xy", "xy"):
        code += [f"movw {P1[0]}, r0"] if tab.dep[1] == tab.dep[0] else []
    code += ["movw r30, r0", f"subi r30, lo8(-(%[tab] + {toff[0] * B}))", f"sbci r31, hi8(-(%[tab] + {toff[0] * B}))"]
    if tab.dep != ("xy", "xy") and tab.dep[1] != tab.dep[0]:
        code += _offset(tab, tab.dep[1]) + [f"movw {P1[0]}, r0"]
    return code


def output_1d(tab, o: int) -> list[str]:
    """A 1-D output (dep "y": e00, e01 along y with fy; "x": e00, e10 with fx = a + w11)."""
    B = tab.bits // 8
    W = tab.grid.W
    code = [f"lpm {E[0]}, Z+", f"lpm {E[1]}, Z+"]
    code += _acc_init(B, W)
    code += [f"lpm {D[0]}, Z+", f"lpm {D[1]}, Z+", f"sub {D[0]}, {E[0]}", f"sbc {D[1]}, {E[1]}"]
    if tab.dep[o] == "y":
        return code + _macsu(W, FY)
    if W == 16:
        code += [f"movw {U[0]}, {AW[0]}", f"add {U[0]}, {W11[0]}", f"adc {U[1]}, {W11[1]}"]
    else:
        code += [f"mov {U[0]}, {AW[0]}", f"add {U[0]}, {W11[0]}"]
    return code + _macsu(W, None)


def _acc_init(B: int, W: int) -> list[str]:
    """A = e00 2^W (int16) or 0 (int32, after reading e00's high word)."""
    if B == 4:
        return [f"lpm {E[2]}, Z+", f"lpm {E[3]}, Z+"] + [f"clr {r}" for r in A]
    if W == 16:
        return [f"clr {A[0]}", f"clr {A[1]}", f"movw {A[2]}, {E[0]}"]
    return [f"clr {A[0]}", f"mov {A[1]}, {E[0]}", f"mov {A[2]}, {E[1]}",
            f"mov {A[3]}, {E[1]}", f"lsl {A[3]}", f"sbc {A[3]}, {A[3]}"]


def output_acc(tab, o: int, negate_odd: bool = True) -> list[str]:
    """Table part of output o: acc in A (Z at the cell of output o on entry; on exit Z is the
    cell + NX + 2 entries); negate_odd=False leaves an odd output's negation to the caller."""
    g = tab.grid
    B = tab.bits // 8
    W = g.W
    skip = ["adiw r30, 2"] if B == 4 else []
    if tab.dep[o] != "xy":
        return output_1d(tab, o) + _combine(tab, o, negate_odd)
    code = [f"lpm {E[0]}, Z+", f"lpm {E[1]}, Z+"] + _acc_init(B, W)
    code += [f"lpm {D[0]}, Z+", f"lpm {D[1]}, Z+"] + skip + [f"sub {D[0]}, {E[0]}", f"sbc {D[1]}, {E[1]}"]
    code += _macsu(W, AW)
    adj = g.n[0] * B - 2 * B
    code += [f"subi r30, lo8({-adj})", f"sbci r31, hi8({-adj})"]
    code += [f"lpm {F[0]}, Z+", f"lpm {F[1]}, Z+"] + skip
    code += [f"movw {D[0]}, {F[0]}", f"sub {D[0]}, {E[0]}", f"sbc {D[1]}, {E[1]}"] + _macsu(W, FY)
    code += [f"lpm {D[0]}, Z+", f"lpm {D[1]}, Z+"] + skip + [f"sub {D[0]}, {F[0]}", f"sbc {D[1]}, {F[1]}"]
    code += _macsu(W, W11)
    return code + _combine(tab, o, negate_odd)


def _combine(tab, o: int, negate_odd: bool = True) -> list[str]:
    """int32 entries: acc = e00 + (S >> W); then the odd output's negation (if negate_odd)."""
    B = tab.bits // 8
    W = tab.grid.W
    code = []
    if B == 4:  # acc = e00 + (S >> W)
        if W == 16:
            code += [f"movw {D[0]}, {A[2]}", f"clr {F[0]}", f"sbrc {D[1]}, 7", f"com {F[0]}",
                     f"movw {A[0]}, {E[0]}", f"movw {A[2]}, {E[2]}",
                     f"add {A[0]}, {D[0]}", f"adc {A[1]}, {D[1]}", f"adc {A[2]}, {F[0]}", f"adc {A[3]}, {F[0]}"]
        else:
            code += [f"mov {D[0]}, {A[1]}", f"mov {D[1]}, {A[2]}", f"mov {F[0]}, {A[3]}", f"clr {F[1]}",
                     f"sbrc {F[0]}, 7", f"com {F[1]}", f"movw {A[0]}, {E[0]}", f"movw {A[2]}, {E[2]}",
                     f"add {A[0]}, {D[0]}", f"adc {A[1]}, {D[1]}", f"adc {A[2]}, {F[0]}", f"adc {A[3]}, {F[1]}"]
    return code + (odd_negation(tab, o) if negate_odd else [])


def odd_negation(tab, o: int) -> list[str]:
    """A = -A where output o is odd in a folded axis whose input was negative."""
    return [f"sbrs {NEG}, {o}", "rjmp 1f"] + negate(A) + ["1:"] if tab.odd[o].any() else []


def finish(o: int, shift: int, offset: int, code_range) -> list[str]:
    """out[o] = offset + ((A + 2^(s-1)) >> s), DAC clamp, stored to X+."""
    code = []
    if shift > 0:
        code += add_const(A, 1 << (shift - 1)) + sar_to(A, shift, U[0])
    if offset:
        code += add_const(A, offset)
    if code_range is not None:
        lo, hi = (int(v) for v in code_range)
        code.append(f"nnik_satge {', '.join(A)}, {hi + 1}, {hi}, {U[0]}")
        code.append(f"nnik_satlt {', '.join(A)}, {lo}, {lo}, {U[0]}")
    code += [f"st X+, {r}" for r in A]
    return code


def clobbers(lines: list[str]) -> list[str]:
    """The registers the assembly writes or reads (r24 is the flag operand, r26-r31 X and Z
    operands, r1 is restored): gcc saves and restores the call-saved ones among them. A pair
    instruction (movw, adiw, sbiw) names only the low register of each pair it touches."""
    used = set()
    for ln in lines:
        regs = [int(r) for r in re.findall(r"\br(\d+)\b", ln)]
        used.update(regs)
        if ln.split()[:1] and ln.split()[0] in PAIR_OPS:
            used.update(r + 1 for r in regs)
    regs = sorted(r for r in used if r not in (1, 24) and r < 26)
    return [f"r{r}" for r in regs] + ["memory"]


def saved_registers(lines: list[str]) -> int:
    """Call-saved registers (r2-r17) the prologue pushes and the epilogue pops."""
    return sum(1 for r in clobbers(lines) if r != "memory" and 2 <= int(r[1:]) <= 17)


def wrap(lines: list[str], tabsym: str) -> str:
    from nnik.emit.avr_asm import asm_statement

    return "\n".join([*asm_statement(lines, f'[tab] "i" ({tabsym})', clobbers(lines)), "    return flag;"])


def body(impl, ctx, base_hook=None, after_clamp=None) -> str:
    """The whole function body (see :func:`lines`)."""
    return wrap(lines(impl, ctx, base_hook, after_clamp), f"{impl.problem.name}_tab")


def lines(impl, ctx, base_hook=None, after_clamp=None) -> list[str]:
    """The assembly lines. base_hook(o) -> lines turning A (table acc of output o) into the
    total before rounding (the hybrid's base); Z/X must be preserved by it."""
    tab = impl.table
    g = tab.grid
    code = input_stage(impl, ctx["flipmask"], after_clamp)
    code += pointer(tab, ctx["toff"]) + weights(g.W)
    nn = g.n[0] * g.n[1]
    B = tab.bits // 8
    for o in range(2):
        if o == 1 and tab.dep == ("xy", "xy"):
            adj = nn * B - (g.n[0] + 2) * B
            code += [f"subi r30, lo8({-adj})", f"sbci r31, hi8({-adj})"]
        elif o == 1:
            k1 = ctx["toff"][1] * B
            code += [f"movw r30, {P1[0]}", f"subi r30, lo8(-(%[tab] + {k1}))", f"sbci r31, hi8(-(%[tab] + {k1}))"]
        code += output_acc(tab, o, negate_odd=base_hook is None)
        if base_hook is not None:  # the base first, then base + residual negated together
            code += base_hook(o) + odd_negation(tab, o)
        fin = impl.final_stage()
        code += finish(o, fin["final_shift"][o], fin["final_off_int"][o], impl.problem.code_range)
    code += ["clr r1", "clr %[flag]", "bld %[flag], 0"]
    return code
