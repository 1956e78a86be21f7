"""PIC18 (SDCC pic16) body of the fast kernel.

SDCC cannot bind C variables to inline-assembly operands, so the network runs on a small
work area, one struct in one RAM bank, with the gpasm macros of codegen/runtime/nnik_kernel.h
(NNIK_P18_*) strung into one __asm__ statement.  The clamp of the inputs and the int32 I/O
through the caller's pointers stay in C.

Supported shape: 2 inputs, one hidden layer of the fast tanh (node step 2^8 or 2^7), 2
outputs.  Anything else uses the value code (portable C) on PIC18 too.
"""

from __future__ import annotations

from nnik.implementations.mlp import fastc_avr
from nnik.implementations.mlp.fixedpoint import ACT_FRAC

# byte offsets in the work struct
OFF = {"v": 0, "o": 8, "x": 16, "a": 20, "h": 24, "y": 26, "fl": 28, "w": 29, "r": 35}


# the assembly is unrolled (about 350 bytes of flash per hidden neuron): wider layers use
# the value code, which loops over tables beyond fastc.UNROLL_MAX_WEIGHTS
ASM_MAX_HIDDEN = 32


def supported(im) -> bool:
    return (im.shape[0] == 2 and im.shape[-1] == 2 and len(im.hidden) == 1 and im.shape[1] <= ASM_MAX_HIDDEN
            and all(4 <= L.tanh_step <= 8 and 1 <= L.sh <= 31 for L in im.hidden))


def _i32(v: int) -> str:
    v = int(v)
    return "(-2147483647L - 1)" if v == -(2**31) else f"{v}L"


def _output_stage(im, sym: str, at) -> list[str]:
    """total = [C + (o >> e)] + affine base, out = total >> F (halves in the start values),
    DAC clamp; in place in o[k]."""
    o = im.out
    e = ACT_FRAC + o.g - o.F
    R = at("r")
    lines = []
    for k in range(2):
        A = at("o", 4 * k)
        if e > 0:
            lines += [f"NNIK_P18_SAR32_8({A})"] * (e // 8) + [f"NNIK_P18_SAR32_1({A})"] * (e % 8)
            lines.append(f"NNIK_P18_ADD32C({A}, {int(o.C[k]) + (1 << (o.F - 1))})")
        if o.residual:
            for j in range(2):
                a = fastc_avr.affine_a(o, k, j)
                c = int(im.inp.lo[j] - im.inp.mid[j])
                ca = (c * a) & (2**48 - 1)
                lines.append(f"NNIK_P18_SET48({R}, {ca & 0xFFFFFFFF}, {ca >> 32})")
                op, opc = ('"subwf"', '"subwfb"') if a < 0 else ('"addwf"', '"addwfc"')
                ab = abs(a)
                for jb in range(4):
                    b = (ab >> (8 * jb)) & 0xFF
                    if not b:
                        continue
                    for i in range(3):
                        off = i + jb
                        wb = f'"{sym}+{OFF["w"] + 3 * j + i}"'
                        if off == 5:
                            lines.append(f"NNIK_P18_P48TOP({op}, {R}, {wb}, {b})")
                            continue
                        lines.append(f'NNIK_P18_P48({op}, {opc}, {R}, "{off}", {wb}, {b})')
                        if off + 2 <= 5:
                            lines.append("NNIK_P18_C48_0")
                            lines += [f'NNIK_P18_C48({opc}, {R}, "{q}")' for q in range(off + 2, 6)]
                G = int(o.G[k][j])
                lines += [f"NNIK_P18_SHL48_1({R})"] * max(0, 16 - G)
                r2 = f'"{sym}+{OFF["r"] + 2}"'
                lines += [f"NNIK_P18_SAR32_1({r2})"] * max(0, G - 16)
                lines.append(f"NNIK_P18_ADD32({A}, {r2})")
        F = int(o.F)
        if F >= 16:
            lines += [f"NNIK_P18_SAR1_2({A})"] * (F - 16) + [f"NNIK_P18_OUT_({A})"]
        else:
            lines += [f"NNIK_P18_SAR32_8({A})"] * (F // 8) + [f"NNIK_P18_SAR32_1({A})"] * (F % 8)
        if o.code_range is not None:
            lo, hi = (int(v) for v in o.code_range)
            lines.append(f'NNIK_P18_SATGE({A}, {hi + 1}, {hi}, "{sym}_cg{k}")')
            lines.append(f'NNIK_P18_SATLT({A}, {lo}, {lo}, "{sym}_cl{k}")')
    return lines


def body(cx, start, out_start) -> str | None:
    im = cx.im
    if not supported(im):
        return None
    o = im.out
    L = im.hidden[0]
    e = ACT_FRAC + o.g - o.F
    w = f"{cx.name}_p18"
    sym = f"_{w}"

    def at(field: str, k: int = 0) -> str:
        return f'"{sym}+{OFF[field] + k}"'

    A, H, Y = at("a"), at("h"), at("y")
    X = [at("x", 0), at("x", 2)]
    Ob = [at("o", 0), at("o", 4)]

    def mac(acc: str, x: str, wt: int) -> list[str]:
        wt = int(wt)
        if wt == 0:
            return []
        kind = ("MSUBU" if wt < 0 else "MACU") + ("8" if abs(wt) < 256 else "")
        return [f"NNIK_P18_{kind}({acc}, {x}, {abs(wt)})"]

    tab = f"_{cx.table(L.tanh_m, L.tanh_step)}"
    asm = [f'"BANKSEL {sym}\\n movlw UPPER({tab})\\n movwf 0xFF8, A\\n"']
    out_asm = fastc_avr.output_asm_ok(im)
    fold = e == 0 and out_asm
    for j in range(2):
        lo, hi, mid, K = (int(im.inp.lo[j]), int(im.inp.hi[j]), int(im.inp.mid[j]), int(im.inp.K[j]))
        c = lo - mid + ((1 << K) >> 1) + (1 << (15 + K))
        V = at("v", 4 * j)
        asm.append(f'NNIK_P18_INW({V}, {at("fl")}, {lo}, {hi - lo}, "{sym}_in{j}")')
        if o.residual and out_asm:
            asm.append('"' + " ".join(f"movff {sym}+{OFF['v'] + 4 * j + i}, {sym}+{OFF['w'] + 3 * j + i}\\n"
                                       for i in range(3)) + '"')
        asm.append(f"NNIK_P18_INX({V}, {c})")
        asm += [f"NNIK_P18_SHR24_1({V})"] * K
        asm.append(f'"movff {sym}+{OFF["v"] + 4 * j}, {sym}+{OFF["x"] + 2 * j}\\n'
                   f' movff {sym}+{OFF["v"] + 4 * j + 1}, {sym}+{OFF["x"] + 2 * j + 1}\\n"')
    for k in range(2):
        asm.append(f"NNIK_P18_SET32({Ob[k]}, {int(out_start(im, k, fold))})")
    for i in range(L.W.shape[0]):
        asm.append(f"NNIK_P18_SET32({A}, {int(start(L, i))})")
        for j in range(2):
            asm += mac(A, X[j], L.W[i, j])
        if L.saturate:
            if L.sh + 15 < 31:
                asm.append(f'NNIK_P18_SATGE({A}, {32768 << L.sh}, {32767 << L.sh}, "{sym}_g{i}")')
            if L.sh + 15 < 32:
                asm.append(f'NNIK_P18_SATLT({A}, {-(32767 << L.sh)}, {-(32767 << L.sh)}, "{sym}_l{i}")')
        if L.sh < 8:
            asm += [f"NNIK_P18_SHL1_4({A})"] * (16 - L.sh)
        elif L.sh < 16:
            asm += [f"NNIK_P18_SHL1({A})"] * (16 - L.sh)
        else:
            asm += [f"NNIK_P18_SAR1_2({A})"] * (L.sh - 16)
        if L.tanh_step in (7, 8):
            asm.append(f"NNIK_P18_TANH{L.tanh_step}({H}, {Y}, {A}, {tab})")
        else:
            s_ = L.tanh_step
            asm.append(f"NNIK_P18_TCOPY({Y}, {A})")
            asm += [f"NNIK_P18_SAR16({Y})"] * (s_ - 1)
            asm += [f"NNIK_P18_FSHL({A})"] * (8 - s_)
            asm.append(f"NNIK_P18_TANHS_({H}, {Y}, {A}, {tab}, {1 << (16 - s_)})")
        for k in range(2):
            asm += mac(Ob[k], H, o.V[k, i])
    if fold and not o.residual and o.code_range is None and o.F >= 16:
        for k in range(2):
            asm += [f"NNIK_P18_SAR1_2({Ob[k]})"] * (o.F - 16)
            asm.append(f"NNIK_P18_OUT_({Ob[k]})")
    elif out_asm:
        asm += _output_stage(im, sym, at)
    lines = [
        "/* work area of the PIC18 kernel: one struct, one RAM bank */",
        "static struct {",
        "    int32_t v[2];   /* +0 */",
        "    int32_t o[2];   /* +8: output accumulators, then the outputs */",
        "    uint16_t x[2];  /* +16: layer-1 inputs, offset binary */",
        "    uint8_t a[4];   /* +20: neuron accumulator */",
        "    uint8_t h[2];   /* +24: tanh output, offset binary */",
        "    uint8_t y[2];   /* +26: scratch */",
        "    int8_t fl;      /* +28: an input was clamped */",
        "    uint8_t w[6];   /* +29: clamp(v) - lo, 3 bytes per input (affine base) */",
        "    uint8_t r[6];   /* +35: 48-bit product (affine base) */",
        f"}} {w};",
        "",
        f"int8_t {cx.name}_ik(const int32_t in_um[{cx.NAME}_N_IN], int32_t out[{cx.NAME}_N_OUT])",
        "{",
        f"    {w}.v[0] = in_um[0];",
        f"    {w}.v[1] = in_um[1];",
        f"    {w}.fl = 0;",
    ]
    lines.append("    __asm__(")
    lines += [f"        {a}" for a in asm]
    lines.append("    );")
    lines += [f"    out[{k}] = {w}.o[{k}];" for k in range(2)]
    if not out_asm:
        lines += cx.finish_lines()
    lines += [f"    return {w}.fl;", "}"]
    return "\n".join(lines)
