"""The `poly` family's C: the statements of one integer program (nnik.implementations.poly.int_model)
for the three paths of codegen/templates/poly_ik.c.j2 -- portable C99, avr-gcc (signed hardware
multiply in inline assembly) and SDCC pic16 (one __asm__ block on a work area, MULWF products).
All three give the bits of poly_int.evaluate."""

from __future__ import annotations

from nnik.implementations.c_common import i32
from nnik.implementations.poly.int_model import Program


def _k16(v: int) -> str:
    return f"((int16_t){int(v)})"


def _operand(b) -> str:
    return b if isinstance(b, str) else _k16(b)


def lsb_used(prog: Program) -> list[str]:
    """Which of rx, ry (the bits the input shift drops) the outputs use."""
    return [r for r in ("rx", "ry") if any(A == r for o in prog.outs for A, _, _ in o.terms)]


def input_lines(maps, lo, hi, indent="    ", name: str | None = None, used=()) -> list[str]:
    """Clamp, then u, v (and rx, ry: into NAME_r[] on avr-gcc, else into int16 locals)."""
    out = []
    for a, (var, src) in enumerate((("u", "x"), ("v", "y"))):
        out += [f"if ({src} < {i32(lo[a])}) {{ {src} = {i32(lo[a])}; clamped = 1; }}",
                f"else if ({src} > {i32(hi[a])}) {{ {src} = {i32(hi[a])}; clamped = 1; }}"]
    for a, (var, src) in enumerate((("u", "x"), ("v", "y"))):
        m = maps[a]
        d = f"({src} - {i32(m.c)})" if m.c else src
        rname = ("rx", "ry")[a]
        if rname in used:
            mask = (1 << m.k) - 1
            dst = f"{name}_r[{a}]" if name else rname
            typ = "uint8_t" if name else "int16_t"
            out.append(f"{dst} = ({typ})((uint16_t)(uint32_t){d} & {mask}u);")
        if m.k > 0 and name and m.k <= 8:
            out.append(f"{src} = {d};")
            out.append(f"{name.upper()}_ASR24({src}, {m.k});")
            out.append(f"{var} = (int16_t){src};")
        elif m.k > 0:
            out.append(f"{var} = (int16_t)nnik_sar32({d}, {m.k});")
        elif m.k == 0:
            out.append(f"{var} = (int16_t){d};")
        else:
            out.append(f"{var} = (int16_t)(uint16_t)((uint16_t)(int16_t){d} << {-m.k});")
    return [indent + s for s in out]


def output_lines(prog: Program, code_range, mul, indent="    ", name: str | None = None) -> list[str]:
    """The sums, rounding and DAC clamp; `mul(A, B)` is the int32 product expression. With
    `name` (avr-gcc), a rounding shift of 16..31 bits whose result fits int16 takes the top two
    bytes and shifts them."""
    out = []
    for k, o in enumerate(prog.outs):
        out.append(f"n = {i32(o.C)};")
        for A, B, t in o.terms:
            prod = mul(A, _operand(B))
            out.append(f"n += nnik_sar32({prod}, {t});" if t else f"n += {prod};")
        lo_b, hi_b = prog.bounds[f"out{k}"]
        r_lo, r_hi = (lo_b + (1 << (o.s - 1))) >> o.s, (hi_b + (1 << (o.s - 1))) >> o.s
        if name and 16 <= o.s and -32768 <= r_lo and r_hi <= 32767:
            out.append(f"w = (uint16_t)((uint32_t)(n + {i32(1 << (o.s - 1))}) >> 16);")
            if o.s > 16:
                out.append(f"{name.upper()}_ASR16(w, {o.s - 16});")
            out.append(f"n = {i32(o.offset)} + (int16_t)w;")
        else:
            out.append(f"n = {i32(o.offset)} + nnik_sar32(n + {i32(1 << (o.s - 1))}, {o.s});")
        if code_range is not None:
            lo_, hi_ = (i32(v) for v in code_range)
            out += [f"if (n < {lo_}) n = {lo_};", f"else if (n > {hi_}) n = {hi_};"]
        out.append(f"out[{k}] = n;")
    return [indent + s for s in out]


def portable_steps(prog: Program, indent="    ") -> list[str]:
    out = []
    for st in prog.steps:
        e = f"(int32_t){st.a} * {_operand(st.b)}"
        if st.K:
            e += f" + {i32(st.K)}"
        if st.f:
            e = f"nnik_sar32({e}, {st.f})"
        if st.L is not None:
            e = f"{e} + {_operand(st.L)}"
        out.append(f"{st.dst} = (int16_t)({e});")
    return [indent + s for s in out]


def avr_steps(prog: Program, name: str, indent="    ") -> list[str]:
    """p = a * b (MULS/MULSU), p += K, bits f..f+15 by a short shift of the top bytes, + L
    (mod 2^16: only the final value must fit int16)."""
    out = []
    for st in prog.steps:
        out.append(f"p = {name}_mul({st.a}, {_operand(st.b)});")
        if st.K:
            out.append(f"p += {i32(st.K)};")
        if st.f < 16:
            out.append(f"{name.upper()}_SHL8_24(p, {16 - st.f});")
        out.append(f"w = (uint16_t)((uint32_t)p >> 16);")
        if st.f > 16:
            out.append(f"{name.upper()}_ASR16(w, {st.f - 16});")
        if st.L is not None:
            out.append(f"w = (uint16_t)(w + (uint16_t){_operand(st.L)});")
        out.append(f"{st.dst} = (int16_t)w;")
    return [indent + s for s in out]


def values(prog: Program) -> list[str]:
    return ["u", "v"] + lsb_used(prog) + [st.dst for st in prog.steps]
