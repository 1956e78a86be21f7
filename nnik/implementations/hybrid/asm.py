"""The hybrid's affine base in the AVR and PIC18 assembly of the table
(:mod:`nnik.implementations.lut.avr`, :mod:`nnik.implementations.lut.p18`).

The base of each output, C + Ax tx + Ay ty (24-bit unsigned t times an int16 constant, modulo
2^32), is computed right after the clamp and parked in out[o] (AVR) or the work struct's o[o]
(PIC18); after the table, total = base + (acc >> align) is rounded and stored over it.
"""

from __future__ import annotations

from nnik.implementations.lut import avr as lut_avr


from nnik.implementations.lut import p18 as lut_p18
BASE = ("r22", "r23", "r24", "r25")
TX = ("r10", "r11", "r12")
K = "r16"


def avr_mac_const(acc, t, k: int) -> list[str]:
    """acc (4 bytes) += t (3 bytes, unsigned) * k (|k| < 2^16), modulo 2^32."""
    a = abs(int(k))
    op, opc = ("add", "adc") if k >= 0 else ("sub", "sbc")
    code = []
    for j in range(2):
        kb = (a >> (8 * j)) & 0xFF
        if not kb:
            continue
        code.append(f"ldi {K}, {kb}")
        for i in range(3):
            off = i + j
            if off > 3:
                continue
            code.append(f"mul {t[i]}, {K}")
            if off == 3:
                code.append(f"{op} {acc[3]}, r0")
                continue
            code += [f"{op} {acc[off]}, r0", f"{opc} {acc[off + 1]}, r1"]
            code += [f"{opc} {acc[q]}, {lut_avr.ZERO}" for q in range(off + 2, 4)]
    return code


def _avr_align(al: int) -> list[str]:
    A = lut_avr.A
    if al > 0:
        return lut_avr.sar_to(A, al, lut_avr.U[0])
    return [x for _ in range(-al) for x in (f"lsl {A[0]}", f"rol {A[1]}", f"rol {A[2]}", f"rol {A[3]}")]


def avr_body(impl, ctx) -> str:
    return lut_avr.wrap(avr_lines(impl, ctx), f"{impl.problem.name}_tab")


def avr_lines(impl, ctx) -> list[str]:
    base = impl.base
    A = lut_avr.A

    def after_clamp(a):
        if a == 0:
            return [f"movw {TX[0]}, {A[0]}", f"mov {TX[2]}, {A[2]}"]
        code = []
        for o in range(2):
            c = int(base[o, 0]) & 0xFFFFFFFF
            code += [f"ldi {BASE[i]}, {(c >> (8 * i)) & 0xFF}" for i in range(4)]
            code += avr_mac_const(BASE, TX, int(base[o, 1])) + avr_mac_const(BASE, A[:3], int(base[o, 2]))
            code += [f"st X+, {r}" for r in BASE]
        return code + ["sbiw r26, 8"]

    def hook(o):
        code = _avr_align(impl.align[o])
        for i in range(4):
            code += [f"ld {lut_avr.U[0]}, X+", f"{'add' if i == 0 else 'adc'} {A[i]}, {lut_avr.U[0]}"]
        return code + ["sbiw r26, 4"]

    return lut_avr.lines(impl, ctx, base_hook=hook, after_clamp=after_clamp)


def p18_mac_const(asm, d: list[str], src: list[str], k: int) -> None:
    """d (4 byte addresses) += src (3 bytes, unsigned) * k (|k| < 2^16), modulo 2^32."""
    a = abs(int(k))
    op, opc = ("addwf", "addwfc") if k >= 0 else ("subwf", "subwfb")
    for j in range(2):
        kb = (a >> (8 * j)) & 0xFF
        if not kb:
            continue
        for i in range(3):
            off = i + j
            if off > 3:
                continue
            asm += [f"movf {src[i]}, W, B", f"mullw {kb}", f"movf {lut_p18.PRODL}, W, A", f"{op} {d[off]}, F, B"]
            if off == 3:
                continue
            asm += [f"movf {lut_p18.PRODH}, W, A", f"{opc} {d[off + 1]}, F, B"]
            if off + 2 <= 3:
                asm += ["movlw 0"] + [f"{opc} {d[q]}, F, B" for q in range(off + 2, 4)]


def p18_body(impl, ctx) -> str:
    return lut_p18.render(impl, p18_items(impl, ctx), f"{impl.problem.name}_p18")


def p18_items(impl, ctx) -> list:
    base = impl.base

    def after_clamp(asm, a):
        for o in range(2):
            if a == 0:
                c = int(base[o, 0]) & 0xFFFFFFFF
                for i in range(4):
                    asm += [f"movlw {(c >> (8 * i)) & 0xFF}", f"movwf {asm.at('o', 4 * o + i)}, B"]
            p18_mac_const(asm, [asm.at("o", 4 * o + i) for i in range(4)], [asm.at("v", 4 * a + i) for i in range(3)],
                          int(base[o, 1 + a]))

    def hook(asm, o):
        al = impl.align[o]
        if al > 0:
            asm.sar("a", al)
        for _ in range(-al):
            asm += [f"bcf {lut_p18.STATUS}, 0, A"] + [f"rlcf {asm.at('a', i)}, F, B" for i in range(4)]
        for i in range(4):
            asm += [f"movf {asm.at('o', 4 * o + i)}, W, B", f"{'addwf' if i == 0 else 'addwfc'} {asm.at('a', i)}, F, B"]

    return lut_p18.items(impl, ctx, base_hook=hook, after_clamp=after_clamp)
