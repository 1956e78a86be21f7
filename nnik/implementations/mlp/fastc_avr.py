"""AVR body of the fast kernel: the whole network as one avr-gcc asm statement.

Built from the assembler macros of codegen/runtime/nnik_kernel.h (NNIK_AVR_ASM_MACROS), with
registers allocated here (gcc saves the call-saved ones it is told are clobbered):

    r2-r5 o0, r6-r9 o1 (output accumulators)   r10:r11 x0, r12:r13 x1 (layer-1 inputs)
    r14 zero   r18:r19 weight / table scratch   r20-r23 neuron accumulator
    r24:r25 tanh output   Z in_um, then tables   X out   T flag: an input was clamped

Supported shape: 2 inputs, one hidden layer of the fast tanh (node step 2^8 or 2^7), 2
outputs.  Anything else uses the value code (portable C primitives) on AVR too.
"""

from __future__ import annotations

import numpy as np

from nnik.emit.avr_asm import asm_statement
from nnik.implementations.mlp.fixedpoint import ACT_FRAC

ACC = ("r20", "r21", "r22", "r23")
O = (("r2", "r3", "r4", "r5"), ("r6", "r7", "r8", "r9"))
X = (("r10", "r11"), ("r12", "r13"))
ZERO = "r14"
T0, T1 = "r18", "r19"
H = ("r24", "r25")
# r24 is the flag operand (the return register; scratch inside the block, "=&r")
CLOBBERS = ["r0"] + [f"r{i}" for i in range(2, 15)] + [f"r{i}" for i in range(18, 24)] + ["r25", "memory"]
# (Z and X are operands: in_um, then table reads; out)


# the assembly is unrolled (about 190 bytes of flash per hidden neuron): wider layers use
# the value code, which loops over tables beyond fastc.UNROLL_MAX_WEIGHTS
ASM_MAX_HIDDEN = 32


def supported(im) -> bool:
    return (im.shape[0] == 2 and im.shape[-1] == 2 and len(im.hidden) == 1 and im.shape[1] <= ASM_MAX_HIDDEN
            and all(4 <= L.tanh_step <= 8 and 1 <= L.sh <= 31 for L in im.hidden))


def _mac(acc, x, w: int) -> list[str]:
    w = int(w)
    if w == 0:
        return []
    a, neg = abs(w), w < 0
    if a < 256:
        return [f"nnik_{'msubu8' if neg else 'macu8'} {', '.join(acc)}, {x[0]}, {x[1]}, {a}, {T0}, {ZERO}"]
    return [f"nnik_{'msubu' if neg else 'macu'} {', '.join(acc)}, {x[0]}, {x[1]}, {a}, {T0}, {T1}, {ZERO}"]


def _t_bytes(sh: int) -> tuple[list[str], str, str]:
    """Shift the accumulator so that bits sh..sh+15 are in r23:r22; returns (code, th, tf)."""
    a0, a1, a2, a3 = ACC
    code = []
    if sh < 8:
        for _ in range(16 - sh):
            code += [f"lsl {a0}", f"rol {a1}", f"rol {a2}", f"rol {a3}"]
    elif sh < 16:
        for _ in range(16 - sh):
            code += [f"lsl {a1}", f"rol {a2}", f"rol {a3}"]
    elif sh > 16:
        for _ in range(sh - 16):
            code += [f"asr {a3}", f"ror {a2}"]
    return code, a3, a2


def _saturate(sh: int) -> list[str]:
    """Clamp the accumulator so that acc >> sh is in [-32767, 32767] (the model's clamp of T)."""
    code = []
    if sh + 15 < 31:
        code.append(f"nnik_satge {', '.join(ACC)}, {32768 << sh}, {32767 << sh}, {T0}")
    if sh + 15 < 32:
        code.append(f"nnik_satlt {', '.join(ACC)}, {-(32767 << sh)}, {-(32767 << sh)}, {T0}")
    return code


def output_asm_ok(im) -> bool:
    """The output stage (shift, constant, affine base, rounding, DAC clamp) in assembly."""
    o = im.out
    e = ACT_FRAC + o.g - o.F
    if e < 0 or not 1 <= o.F <= 31:
        return False
    if o.residual:
        maxd = np.maximum(im.inp.hi - im.inp.mid, im.inp.mid - im.inp.lo)
        for k in range(2):
            for j in range(2):
                a = affine_a(o, k, j)
                if not (8 <= int(o.G[k][j]) <= 24 and abs(a) < 2**31 and int(maxd[j]) < 2**22
                        and int(im.inp.hi[j] - im.inp.lo[j]) < 2**23):
                    return False
    return True


def affine_a(o, k: int, j: int) -> int:
    """The affine coefficient A = A1 2^P + A0: the base adds floor(d A / 2^G)."""
    return (int(o.A1[k][j]) << int(o.P[k][j])) + int(o.A0[k][j])


def _sar(regs, n: int) -> list[str]:
    """Arithmetic right shift of a multi-byte register value by n (byte moves first)."""
    regs = list(regs)
    code = []
    for _ in range(n // 8):
        code += [f"mov {regs[i]}, {regs[i + 1]}" for i in range(len(regs) - 1)]
        code += [f"mov {T0}, {regs[-1]}", f"lsl {T0}", f"sbc {regs[-1]}, {regs[-1]}"]
    for _ in range(n % 8):
        code += [f"asr {regs[-1]}"] + [f"ror {r}" for r in reversed(regs[:-1])]
    return code


def _output_stage(im, lines_w_offset) -> list[str]:
    """Per output: total = [C + (o >> e)] + affine base, out = total >> F (the halves are in
    the start values), clamp to the DAC's codes, store to X+."""
    o = im.out
    e = ACT_FRAC + o.g - o.F
    R = ("r18", "r19", "r20", "r21", "r22", "r23")
    W = (("r10", "r11", "r12"), ("r13", "r25", "r30"))  # w0, w1 (Z is free by now)
    lines = []
    if o.residual:
        lines += ["movw r30, r26"] + [f"ldd {r}, Z+{lines_w_offset + 3 * j + i}"
                                      for j in range(2) for i, r in enumerate(W[j])]
    for k in range(2):
        ok = O[k]
        if e > 0:
            lines += _sar(ok, e)
            lines.append(f"nnik_ldi32 {', '.join(ACC)}, {int(o.C[k]) + (1 << (o.F - 1))}")
            lines += [f"add {ok[0]}, {ACC[0]}"] + [f"adc {ok[i]}, {ACC[i]}" for i in range(1, 4)]
        if o.residual:
            for j in range(2):
                a = affine_a(o, k, j)
                c = int(im.inp.lo[j] - im.inp.mid[j])
                ca = (c * a) & (2**48 - 1)
                lines.append(f"nnik_ldi48 {', '.join(R)}, {ca & 0xFFFFFFFF}, {ca >> 32}")
                lines.append(f"nnik_{'msub48' if a < 0 else 'mac48'} {', '.join(R)}, {', '.join(W[j])}, "
                             f"{abs(a)}, {H[0]}, {ZERO}")
                G = int(o.G[k][j])
                for _ in range(16 - G):
                    lines += [f"lsl {R[1]}"] + [f"rol {r}" for r in R[2:]]
                for _ in range(G - 16):
                    lines += [f"asr {R[5]}"] + [f"ror {r}" for r in reversed(R[2:5])]
                lines += [f"add {ok[0]}, {R[2]}"] + [f"adc {ok[i]}, {R[2 + i]}" for i in range(1, 4)]
        # out = total >> F, as int32 in r20..r23
        F = int(o.F)
        res = ACC
        if F >= 16:
            lines += [f"movw {res[0]}, {ok[2]}"] + [x for _ in range(F - 16) for x in (f"asr {res[1]}", f"ror {res[0]}")]
            lines += [f"mov {res[2]}, {res[1]}", f"lsl {res[2]}", f"sbc {res[2]}, {res[2]}", f"mov {res[3]}, {res[2]}"]
        elif F >= 8:
            lines += [f"mov {res[0]}, {ok[1]}", f"mov {res[1]}, {ok[2]}", f"mov {res[2]}, {ok[3]}"]
            lines += [x for _ in range(F - 8) for x in (f"asr {res[2]}", f"ror {res[1]}", f"ror {res[0]}")]
            lines += [f"mov {res[3]}, {res[2]}", f"lsl {res[3]}", f"sbc {res[3]}, {res[3]}"]
        else:
            lines += [f"movw {res[0]}, {ok[0]}", f"movw {res[2]}, {ok[2]}"] + _sar(res, F)
        if o.code_range is not None:
            lo, hi = (int(v) for v in o.code_range)
            lines.append(f"nnik_satge {', '.join(res)}, {hi + 1}, {hi}, {T0}")
            lines.append(f"nnik_satlt {', '.join(res)}, {lo}, {lo}, {T0}")
        lines += [f"st X+, {r}" for r in res]
    return lines


def body(cx, start, out_start) -> str | None:
    """The AVR function body, or None when the model's shape is not supported here."""
    im = cx.im
    if not supported(im):
        return None
    o = im.out
    L = im.hidden[0]
    e = ACT_FRAC + o.g - o.F
    out_asm = output_asm_ok(im)
    fold = e == 0 and out_asm  # C and the rounding half in the start value of o
    tabs = {}
    lines = ["clr " + ZERO, "clt"]
    for j in range(2):
        lo, hi, mid, K = (int(im.inp.lo[j]), int(im.inp.hi[j]), int(im.inp.mid[j]), int(im.inp.K[j]))
        c = lo - mid + ((1 << K) >> 1) + (1 << (15 + K))
        lines.append(f"nnik_inw {', '.join(ACC)}, {lo}, {hi - lo}, {T0}")
        if o.residual and out_asm:  # keep w = clamp(v) - lo for the affine base, in out[]
            lines += [f"st X+, {ACC[i]}" for i in range(3)]
        lines.append(f"nnik_inx {ACC[0]}, {ACC[1]}, {ACC[2]}, {X[j][0]}, {X[j][1]}, {c}, {K}")
    if o.residual and out_asm:
        lines.append("sbiw r26, 6")
    for k in range(2):
        lines.append(f"nnik_ldi32 {', '.join(ACC)}, {int(out_start(im, k, fold))}")
        lines += [f"movw {O[k][0]}, {ACC[0]}", f"movw {O[k][2]}, {ACC[2]}"]
    for i in range(L.W.shape[0]):
        lines.append(f"nnik_ldi32 {', '.join(ACC)}, {int(start(L, i))}")
        for j in range(2):
            lines += _mac(ACC, X[j], L.W[i, j])
        if L.saturate:
            lines += _saturate(L.sh)
        code, th, tf = _t_bytes(L.sh)
        lines += code
        key = (L.tanh_m, L.tanh_step)
        tab = tabs.setdefault(key, f"%[tab{len(tabs)}]")
        if L.tanh_step in (7, 8):
            lines.append(f"nnik_tanh{L.tanh_step} {H[0]}, {H[1]}, {th}, {tf}, {tab}, {T0}, {T1}, {ZERO}")
        else:
            lines.append(f"nnik_tanhs {H[0]}, {H[1]}, {th}, {tf}, {tab}, {L.tanh_step}, {T0}, {T1}, {ZERO}")
        for k in range(2):
            lines += _mac(O[k], H, o.V[k, i])
    if fold and not o.residual and o.code_range is None and o.F >= 16:
        for k in range(2):
            lines.append(f"nnik_out {', '.join(O[k])}, {o.F}, {T0}, {T1}, {ACC[0]}")
    elif out_asm:
        lines += _output_stage(im, 0)
    else:
        lines += [f"st X+, {r}" for k in range(2) for r in O[k]]
    lines += ["clr r1", "clr %[flag]", "bld %[flag], 0"]
    tab_ops = ", ".join(f'[tab{n}] "i" ({cx.table(m, s)})' for (m, s), n in
                        sorted(((key, int(v[5:-1])) for key, v in tabs.items()), key=lambda t: t[1]))
    text = asm_statement(lines, tab_ops, CLOBBERS)
    if not out_asm:
        text += cx.finish_lines()
    text.append("    return flag;")
    return "\n".join(text)
