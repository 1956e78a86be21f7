"""avr-gcc path of the `poly` family: the whole integer program (nnik.implementations.poly.int_model)
as one inline-assembly block on the hardware multiplier, bit-exact with poly_int.evaluate.

Registers: u in r24:r25 and v in r26:r27 on entry (local register variables), the other int16
values in r2..r13 pairs (allocated by last use), r14 = 0, multiplier operands r16:r17 and
r18:r19 (MULS/MULSU need r16..r23), the product in r20..r23, ``out`` in Z. One step
``dst = ((a * b + K) >> f) + L`` is: movw/ldi the operands, the signed 16 x 16 product
(MULS, MUL, 2 x MULSU: 20 cycles), K added to the bytes it touches, the bits f..f+15 taken by
a short shift of the top bytes, L added mod 2^16 (only the final value must fit int16)."""

from __future__ import annotations

from nnik.implementations.poly.int_model import Program

PAIRS = ["r24", "r26", "r2", "r4", "r6", "r8", "r10", "r12"]
ZERO = "r14"


def _r(pair: str, hi: int = 0) -> str:
    return f"r{int(pair[1:]) + hi}"


def _mul() -> list[str]:
    z = ZERO
    return ["muls r17, r19", "movw r22, r0", "mul r16, r18", "movw r20, r0",
            "mulsu r17, r18", f"sbc r23, {z}", "add r21, r0", "adc r22, r1", f"adc r23, {z}",
            "mulsu r19, r16", f"sbc r23, {z}", "add r21, r0", "adc r22, r1", f"adc r23, {z}"]


def _add_const(regs: list[str], k: int) -> list[str]:
    """regs (low byte first, all r16..r31) += k (mod 2^(8 len)), skipping zero low bytes."""
    n = len(regs)
    k &= (1 << (8 * n)) - 1
    if k == 0:
        return []
    lo = 0
    while (k >> (8 * lo)) & 0xFF == 0:
        lo += 1
    neg = (-(k >> (8 * lo))) & ((1 << (8 * (n - lo))) - 1)
    out = []
    for i in range(lo, n):
        byte = (neg >> (8 * (i - lo))) & 0xFF
        out.append(f"{'subi' if i == lo else 'sbci'} {regs[i]}, {byte}")
    return out


def body(prog: Program, code_range, name: str) -> list[str] | None:
    """The asm statement (C lines), or None when the values do not fit the register pairs.
    The DAC clamp is done in the assembly on the int16 result (or in C after it)."""
    from nnik.implementations.c_common import i32

    c_clamp = []
    # schedule: each output's sum right after the last step it needs (shorter live ranges)
    done_at = {"u": -1, "v": -1, "rx": -1, "ry": -1}
    for i, st in enumerate(prog.steps):
        done_at[st.dst] = i
    out_after = [max([done_at[r] for A, B, _ in o.terms for r in (A, B) if isinstance(r, str)] + [-1])
                 for o in prog.outs]
    events = []  # ("step", i) / ("out", k) in emission order
    for k, a in enumerate(out_after):
        if a < 0:
            events.append(("out", k))
    for i in range(len(prog.steps)):
        events.append(("step", i))
        events += [("out", k) for k, a in enumerate(out_after) if a == i]
    uses: dict[str, int] = {}
    for t, (kind, i) in enumerate(events):
        refs = ([prog.steps[i].a, prog.steps[i].b, prog.steps[i].L] if kind == "step"
                else [r for A, B, _ in prog.outs[i].terms for r in (A, B)])
        for r in refs:
            if isinstance(r, str):
                uses[r] = t
    where = {"u": "r24", "v": "r26"}
    free = [p for p in PAIRS if p not in where.values()]
    used_pairs = set()
    asm = [f"clr {ZERO}"]

    def release(t):
        for name, last in list(uses.items()):
            if last == t and name in where:
                reg = where.pop(name)
                if reg != "r22":
                    free.insert(0, reg)

    def load(reg_lo: str, op) -> list[str]:
        if op in ("rx", "ry"):
            return [f"lds {reg_lo}, {name}_r+{('rx', 'ry').index(op)}", f"clr r{int(reg_lo[1:]) + 1}"]
        if isinstance(op, str):
            return [f"movw {reg_lo}, {where[op]}"]
        v = int(op) & 0xFFFF
        return [f"ldi {reg_lo}, {v & 0xFF}", f"ldi r{int(reg_lo[1:]) + 1}, {v >> 8}"]

    for t, (kind, i) in enumerate(events):
        if kind == "step":
            st = prog.steps[i]
            asm += load("r16", st.a) + load("r18", st.b) + _mul()
            asm += _add_const(["r20", "r21", "r22", "r23"], st.K)
            if st.f <= 16:
                asm += ["lsl r21", "rol r22", "rol r23"] * (16 - st.f)
            else:
                asm += ["asr r23", "ror r22"] * (st.f - 16)
            if isinstance(st.L, str):
                asm += [f"add r22, {where[st.L]}", f"adc r23, {_r(where[st.L], 1)}"]
            elif st.L is not None:
                asm += _add_const(["r22", "r23"], int(st.L))
            release(t)
            nxt = events[t + 1] if t + 1 < len(events) else None
            if (nxt and nxt[0] == "step" and uses.get(st.dst) == t + 1 and prog.steps[nxt[1]].a == st.dst
                    and st.dst not in (prog.steps[nxt[1]].b, prog.steps[nxt[1]].L)):
                where[st.dst] = "r22"  # forwarded: the next step takes it straight from the product
                continue
            if not free:
                return None
            dst = free.pop(0)
            used_pairs.add(dst)
            where[st.dst] = dst
            asm.append(f"movw {dst}, r22")
            continue
        k, o = i, prog.outs[i]
        acc = None
        for j, (A, B, sh) in enumerate(o.terms):
            asm += load("r16", A) + load("r18", B) + _mul()
            asm += ["asr r23", "ror r22", "ror r21", "ror r20"] * sh
            if len(o.terms) == 1:
                break
            if acc is None:
                if len(free) < 2:
                    return None
                acc = (free.pop(0), free.pop(0))
                used_pairs.update(acc)
                asm += [f"movw {acc[0]}, r20", f"movw {acc[1]}, r22"]
            else:
                asm += [f"add {acc[0]}, r20", f"adc {_r(acc[0], 1)}, r21",
                        f"adc {acc[1]}, r22", f"adc {_r(acc[1], 1)}, r23"]
        if not o.terms:
            asm += ["clr r20", "clr r21", "movw r22, r20"]
        elif acc is not None:
            asm += [f"movw r20, {acc[0]}", f"movw r22, {acc[1]}"]
            free += list(acc)
        asm += _add_const(["r20", "r21", "r22", "r23"], o.C + (1 << (o.s - 1)))
        lo_b, hi_b = prog.bounds[f"out{k}"]
        r_lo, r_hi = (lo_b + (1 << (o.s - 1))) >> o.s, (hi_b + (1 << (o.s - 1))) >> o.s
        if 8 <= o.s and -32768 <= r_lo and r_hi <= 32767:
            asm += ["asr r23", "ror r22"] * (o.s - 16) + ["lsl r21", "rol r22", "rol r23"] * (16 - o.s)
            if code_range is not None:
                clo, chi = code_range[0] - o.offset, code_range[1] - o.offset
                if r_lo < clo and -32768 <= clo <= 32767:
                    asm += [f"ldi r20, {clo & 0xFF}", f"ldi r21, {(clo >> 8) & 0xFF}", "cp r22, r20",
                            "cpc r23, r21", "brge 1f", "movw r22, r20", "1:"]
                if r_hi > chi and -32768 <= chi <= 32767:
                    asm += [f"ldi r20, {chi & 0xFF}", f"ldi r21, {(chi >> 8) & 0xFF}", "cp r20, r22",
                            "cpc r21, r23", "brge 1f", "movw r22, r20", "1:"]
                if not (-32768 <= clo <= 32767 and -32768 <= chi <= 32767):
                    c_clamp.append(k)
            asm += ["mov r20, r23", "lsl r20", "sbc r20, r20", "mov r21, r20"]
            res = ["r22", "r23", "r20", "r21"]
        else:
            asm += ["asr r23", "ror r22", "ror r21", "ror r20"] * o.s
            res = ["r20", "r21", "r22", "r23"]
            if code_range is not None:
                c_clamp.append(k)
        asm += _add_const(res, o.offset)
        asm += [f"std Z+{4 * k + b}, {res[b]}" for b in range(4)]
        release(t)
    asm.append("clr r1")
    clob = sorted({ZERO, "r0"} | {f"r{i}" for i in range(16, 24)}
                  | {_r(p, h) for p in used_pairs if p not in ("r24", "r26") for h in (0, 1)},
                  key=lambda r: int(r[1:]))
    lines = ["    {",
             "        register int16_t ru __asm__(\"r24\") = u;",
             "        register int16_t rv __asm__(\"r26\") = v;",
             "        __asm__ __volatile__ ("]
    lines += [f'            "{a}\\n\\t"' for a in asm]
    lines.append('            : "+r" (ru), "+r" (rv)')
    lines.append('            : "z" (out)' + (f', "m" ({name}_r)' if any(x.startswith("lds") for x in asm) else ""))
    lines.append("            : " + ", ".join(f'"{c}"' for c in clob) + ', "memory");')
    lines.append("    }")
    for k in c_clamp:
        lo, hi = i32(code_range[0]), i32(code_range[1])
        lines += [f"    if (out[{k}] < {lo}) out[{k}] = {lo};", f"    else if (out[{k}] > {hi}) out[{k}] = {hi};"]
    return lines
