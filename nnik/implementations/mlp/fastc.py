"""C for the "fast" kernel (nnik.implementations.mlp.kernel): NAME.c from an IntegerModel quantised with kernel="fast".

The network is unrolled with its weights as constants in the code; every operation is a
primitive of codegen/runtime/nnik_kernel.h (avr-gcc asm, SDCC pic16 asm, portable C).  Two
bodies are generated: value code (AVR and portable C) and, for SDCC pic16, code on a small
work area in one RAM bank driven by the PIC18 assembly macros.
"""

from __future__ import annotations

import numpy as np

from nnik.implementations.mlp import tanh as activations
from nnik.emit.c_text import c_comment_safe
from nnik.implementations.mlp import fastc_avr
from nnik.implementations.mlp import fastc_p18
from nnik.implementations.mlp import kernel as kern
from nnik.emit.templating import environment
from nnik.errors import NnikError
from nnik.implementations.mlp.fixedpoint import ACT_FRAC, IntegerModel

# layers with more weights than this are looped over tables instead of unrolled
UNROLL_MAX_WEIGHTS = 256


def _c_list(values, per_line: int = 10, indent: str = "    ") -> str:
    vals = [str(int(v)) for v in np.asarray(values).ravel()]
    return ",\n".join(indent + ", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line))


def _k(NAME: str, v: int) -> str:
    """An accumulator constant: its int32 bits (mod 2^32) and, for instrumented builds, its exact value."""
    v = int(v)
    return f"{NAME}_K(0x{v & 0xFFFFFFFF:08X}UL, {v}LL)"


def _i32(v: int) -> str:
    v = int(v)
    return "(-2147483647L - 1)" if v == -(2**31) else f"{v}L"


class _Ctx:
    def __init__(self, im: IntegerModel):
        self.im = im
        self.name = im.name
        self.NAME = im.name.upper()
        self.tables = {}  # (m, s) -> C name

    def finish_lines(self) -> list[str]:
        """C after an assembly body that left the raw output accumulators in out[]."""
        im = self.im
        o = im.out
        n_in, n_out = im.shape[0], im.shape[-1]
        lines = ["{"]
        lines.append("uint32_t " + ", ".join(f"r{k}_ = (uint32_t)out[{k}]" for k in range(n_out)) + ";")
        if o.residual:
            lines.append("int32_t " + ", ".join(f"d{j}" for j in range(n_in)) + ";")
            for j in range(n_in):
                lo, hi, mid = int(im.inp.lo[j]), int(im.inp.hi[j]), int(im.inp.mid[j])
                lines.append(f"d{j} = (in_um[{j}] < {_i32(lo)}) ? {_i32(lo - mid)} : (in_um[{j}] > {_i32(hi)}) ? "
                             f"{_i32(hi - mid)} : in_um[{j}] - {_i32(mid)};")
        lines += _output_lines(self, [f"r{k}_" for k in range(n_out)], False)
        lines.append("}")
        return ["    " + x if not x.startswith("#") else x for x in lines]

    def table(self, m: int, s: int) -> str:
        key = (m, s)
        if key not in self.tables:
            self.tables[key] = f"{self.name}_tanh_q{m}_{15 - m}_s{s}"
        return self.tables[key]


def _mac_lines(dst: str, x: str, w: int) -> list[str]:
    w = int(w)
    if w == 0:
        return []
    fn = "nnik_macu" if w > 0 else "nnik_msubu"
    return [f"{dst} = {fn}({dst}, {x}, {abs(w)}u);"]


def _tanh_lines(cx: _Ctx, L, t: str, h: str) -> list[str]:
    """h (offset-binary Q15, uint16) from t (offset-binary tanh input, uint16)."""
    if L.tanh_step:
        tab = cx.table(L.tanh_m, L.tanh_step)
        s = L.tanh_step
        if s == 8:
            return [f"{h} = nnik_lerp_u16(&{tab}[(uint8_t)({t} >> 8)], (uint8_t){t});"]
        return [f"{h} = nnik_lerp_u16(&{tab}[{t} >> {s}], (uint8_t)({t} << {8 - s}));"]
    # a portable tanh variant (Q3.12 contract)
    return [f"{h} = (uint16_t)((uint16_t){cx.name}_tanh((int16_t)(uint16_t)({t} ^ 0x8000u)) ^ 0x8000u);"]


def _tu(acc: str, sh: int) -> str:
    return f"nnik_tu16({acc})" if sh == 16 else f"nnik_tu_shr({acc}, {sh})"


def _t_lines(cx: _Ctx, L, acc: str, t: str) -> list[str]:
    NAME = cx.NAME
    sh = L.sh
    if not L.saturate:
        return [f"{t} = {_tu(f'{NAME}_NARROW({acc})', sh)};"]
    # clamp T to +-32767 (Tu 1 .. 65535) where the range analysis cannot exclude it
    lines = ["{", f"    int32_t a_ = nnik_s32({NAME}_NARROW({acc}));"]
    cond = []
    if sh + 15 < 31:  # T > 32767 is reachable only then
        cond.append((f"a_ >= {_i32(32768 << sh)}", "65535u"))
    if sh + 15 < 32:  # T < -32767 likewise
        cond.append((f"a_ < {_i32(-(32767 << sh))}", "1u"))
    if not cond:
        return [f"{t} = {_tu(f'{NAME}_NARROW({acc})', sh)};"]
    for k, (c, val) in enumerate(cond):
        lines.append(f"    {'if' if k == 0 else 'else if'} ({c}) {{ {t} = {val}; {NAME}_SAT_EVENT; }}")
    lines.append(f"    else {{ {t} = {_tu('(uint32_t)a_', sh)}; }}")
    lines.append("}")
    return lines


def _start(L, i: int) -> int:
    """Start value of neuron i's accumulator: bias + rounding half - 32768 * sum(w)."""
    return int(L.B[i]) + (1 << (L.sh - 1)) - 32768 * int(L.W[i].sum())


def _out_start(im: IntegerModel, k: int, fold_half: bool) -> int:
    o = im.out
    e = ACT_FRAC + o.g - o.F
    v = -32768 * int(o.V[k].sum())
    if e > 0:
        v += 1 << (e - 1)  # C itself is added after the shift (C << e need not fit int32)
    elif e == 0:
        v += int(o.C[k])
    if fold_half:
        v += 1 << (o.F - 1)
    return v


def _output_lines(cx: _Ctx, accs: list[str], fold: bool) -> list[str]:
    """Output stage: accumulators -> total (Q F, plus the affine base from d0.. in residual
    mode) -> out[k] rounded (and clamped to the DAC's codes)."""
    im = cx.im
    NAME = cx.NAME
    o = im.out
    e = ACT_FRAC + o.g - o.F
    n_in = im.shape[0]
    body = [(f"/* outputs: total in Q{o.F}{', plus the affine base from d (um)' if o.residual else ''}, "
            f"rounded to {im.unit} */")]
    for k, name in enumerate(accs):
        body.append("{")
        inner = ["int32_t total;"]
        acc = f"nnik_s32({NAME}_NARROW({name}))"
        if fold:
            inner.append("#ifdef NNIK_INSTRUMENT")
            inner.append(f"{cx.name}_last_total[{k}] = {acc} - {_i32(1 << (o.F - 1))};")
            inner.append("#endif")
            inner.append(f"total = nnik_out_shr({NAME}_NARROW({name}), {o.F});")
        else:
            if e > 0:
                inner.append(f"total = {_i32(o.C[k])} + nnik_sar32({acc}, {e});")
            elif e == 0:
                inner.append(f"total = {acc};")
            else:
                inner.append(f"total = {_i32(o.C[k])} + {acc} * {_i32(1 << -e)};")
            if o.residual:
                for j in range(n_in):
                    inner.append(f"total += nnik_sar32(d{j} * (int32_t){int(o.A1[k][j])} + "
                                 f"nnik_sar32(d{j} * (int32_t){int(o.A0[k][j])}, {int(o.P[k][j])}), "
                                 f"{int(o.G[k][j] - o.P[k][j])});")
            inner.append("#ifdef NNIK_INSTRUMENT")
            inner.append(f"{cx.name}_last_total[{k}] = total;")
            inner.append("#endif")
            inner.append(f"total = nnik_sar32(total + {_i32(1 << (o.F - 1))}, {o.F});")
        if o.code_range is not None:
            lo, hi = o.code_range
            inner.append(f"if (total > {_i32(hi)}) {{ total = {_i32(hi)}; {NAME}_SAT_EVENT; }}")
            inner.append(f"else if (total < {_i32(lo)}) {{ total = {_i32(lo)}; {NAME}_SAT_EVENT; }}")
        inner.append(f"out[{k}] = total;")
        body += ["    " + x if not x.startswith("#") else x for x in inner]
        body.append("}")
    return body


def _value_body(cx: _Ctx) -> tuple[str, list[str]]:
    """The C body for AVR / portable builds and the weight tables of looped layers."""
    im = cx.im
    NAME = cx.NAME
    o = im.out
    n_in = im.shape[0]
    n_out = im.shape[-1]
    e = ACT_FRAC + o.g - o.F
    fold = e == 0 and not o.residual
    decl = ["int8_t clamped = 0;"]
    decl.append("const int32_t " + ", ".join(f"v{j} = in_um[{j}]" for j in range(n_in)) + ";")
    if o.residual:
        decl.append("int32_t " + ", ".join(f"d{j}" for j in range(n_in)) + ";")
    decl.append("uint16_t " + ", ".join(f"x{j}" for j in range(n_in)) + ", t, h;")
    decl.append("nnik_acc_t acc, " + ", ".join(f"o{k}" for k in range(n_out)) + ";")
    for li, L in enumerate(im.hidden[:-1]):
        decl.append(f"uint16_t hb{li}[{L.W.shape[0]}];")
    looped = [L.W.size > UNROLL_MAX_WEIGHTS for L in im.hidden]
    if any(looped) or o.V.size > UNROLL_MAX_WEIGHTS:
        decl.append("uint8_t i, j;")
    body: list[str] = []
    tables: list[str] = []
    body.append("/* clamp to the trained domain; layer-1 inputs u = (v - mid + 2^(K-1)) >> K in offset binary */")
    for j in range(n_in):
        lo, hi, mid, K = int(im.inp.lo[j]), int(im.inp.hi[j]), int(im.inp.mid[j]), int(im.inp.K[j])
        # w = v - lo (unsigned) is in [0, hi - lo] inside the domain; then
        # u + 32768 = (d + 2^(K-1)) >> K + 32768 = (w + lo - mid + 2^(K-1) + 2^(15+K)) >> K, all >= 0
        c = lo - mid + ((1 << K) >> 1) + (1 << (15 + K))
        if not 0 <= c and (hi - lo) + c < (1 << (16 + K)):
            raise NnikError(f"input {j}: the layer-1 input does not fit int16")
        body.append("{")
        body.append(f"    uint32_t w_ = (uint32_t)v{j} - (uint32_t){_i32(lo)};")
        body.append(f"    if (w_ > {hi - lo}UL) {{ clamped = 1; w_ = (v{j} < {_i32(lo)}) ? 0UL : {hi - lo}UL; }}")
        if o.residual:
            body.append(f"    d{j} = (int32_t)w_ + {_i32(lo - mid)};")
        body.append(f"    x{j} = nnik_shr24_16(w_ + {c}UL, {K});")
        body.append("}")
    for k in range(n_out):
        body.append(f"o{k} = {_k(NAME, _out_start(im, k, fold))};")
    inputs = [f"x{j}" for j in range(n_in)]
    for li, L in enumerate(im.hidden):
        last = li == len(im.hidden) - 1
        n = L.W.shape[0]
        body.append(f"/* layer {li + 1}: {n} x {L.W.shape[1]}, tanh input Q{L.tanh_m}.{L.tanh_frac} = acc >> {L.sh} */")
        if looped[li]:
            # a large layer: weights from flash, signed multiply-accumulate in a loop
            wname, sname = f"{cx.name}_w{li}", f"{cx.name}_s{li}"
            # start values without the offset-binary term (signed products here): bias + half
            tables.append(f"static NNIK_FLASH const int16_t {wname}[{L.W.size}] = {{\n{_c_list(L.W.ravel())}\n}};\n"
                          f"static NNIK_FLASH const int32_t {sname}[{n}] = {{\n"
                          f"{_c_list([int(L.B[i]) + (1 << (L.sh - 1)) for i in range(n)], per_line=6)}\n}};")
            src = "x" if li == 0 else f"hb{li - 1}"
            if li == 0:
                body.append(f"{{ uint16_t xs[{n_in}]; " + " ".join(f"xs[{j}] = x{j};" for j in range(n_in)))
                src = "xs"
            body.append(f"for (i = 0; i < {n}; i++) {{")
            body.append(f"    acc = (nnik_acc_t)NNIK_RD_I32(&{sname}[i]);")
            body.append(f"    for (j = 0; j < {L.W.shape[1]}; j++)")
            body.append(f"        acc = nnik_mac16(acc, nnik_xs16({src}[j]), "
                        f"NNIK_RD_I16(&{wname}[(uint16_t)i * {L.W.shape[1]} + j]));")
            body += ["    " + x for x in _t_lines(cx, L, "acc", "t")]
            body += ["    " + x for x in _tanh_lines(cx, L, "t", "h")]
            if last:
                for k in range(n_out):
                    body.append(f"    o{k} = nnik_macs(o{k}, h, NNIK_RD_I16(&{cx.name}_v[(uint16_t){k * n} + i]));")
            else:
                body.append(f"    hb{li}[i] = h;")
            body.append("}")
            if li == 0:
                body.append("}")
            inputs = [f"hb{li}[{i}]" for i in range(n)]
            continue
        for i in range(n):
            body.append(f"acc = {_k(NAME, _start(L, i))};")
            for j, x in enumerate(inputs):
                body += _mac_lines("acc", x, L.W[i, j])
            body += _t_lines(cx, L, "acc", "t")
            body += _tanh_lines(cx, L, "t", "h")
            if last:
                for k in range(n_out):
                    body += _mac_lines(f"o{k}", "h", o.V[k, i])
            else:
                body.append(f"hb{li}[{i}] = h;")
        inputs = [f"hb{li}[{i}]" for i in range(n)]
    if any(looped) and looped[-1]:
        tables.append(f"static NNIK_FLASH const int16_t {cx.name}_v[{o.V.size}] = {{\n{_c_list(o.V.ravel())}\n}};")
    body += _output_lines(cx, [f"o{k}" for k in range(n_out)], fold)
    body.append("return clamped;")
    text = "\n".join("    " + x if not x.startswith("#") else x for x in decl + [""] + body)
    return text, tables


def render(im: IntegerModel, scenario_source: str) -> dict[str, str]:
    """{filename: text} for NAME.h and NAME.c of a model quantised with kernel="fast"."""
    if im.kernel != "fast":
        raise NnikError("fastc.render needs a model quantised with kernel='fast'")
    cx = _Ctx(im)
    c_body, weight_tables = _value_body(cx)
    avr_body = fastc_avr.body(cx, _start, _out_start)
    p18_body = fastc_p18.body(cx, _start, _out_start) or ""
    p18_ok = "1" if p18_body else "0"
    tables = []
    for (m, s), cname in cx.tables.items():
        st = kern.ulerp_stats(m, s)
        vals = kern.ulerp_table(m, s)
        tables.append({"name": kern.ulerp_name(m, s), "cname": cname, "m": m, "s": s, "n": int(vals.size),
                           "nodes": _c_list(vals), "max_lsb": st["max_lsb"], "rms_lsb": st["rms_lsb"]})
    uses_variant = any(not L.tanh_step for L in im.hidden)
    tanh_c = activations.render_tanh_c(im.tanh_variant, prefix=im.name) if uses_variant else ""
    tanh_desc = [f"tanh table {kern.ulerp_name(L.tanh_m, L.tanh_step)}" if L.tanh_step
                 else f"tanh variant {im.tanh_variant}" for L in im.hidden]
    o = im.out
    ctx = {
        "name": im.name, "NAME": im.name.upper(), "scenario": c_comment_safe(scenario_source), "model_hash": im.model_hash(),
        "shape": im.shape, "n_in": im.shape[0], "n_out": im.shape[-1], "unit": im.unit, "outputs": im.outputs,
        "lo": im.inp.lo.tolist(), "hi": im.inp.hi.tolist(), "K": im.inp.K.tolist(), "hidden": im.hidden,
        "residual": o.residual, "g": o.g, "F": o.F, "tanh_desc": tanh_desc, "tables": tables, "tanh_c": tanh_c,
        "weight_tables": weight_tables, "c_body": c_body, "p18_body": p18_body, "p18_ok": p18_ok,
        "avr_body": avr_body or "", "avr_ok": "1" if avr_body else "0",
        "p18_asm_only": bool(p18_body) and fastc_avr.output_asm_ok(im),
    }
    env = environment()
    return {f"{im.name}.h": env.get_template("model.h.j2").render(**ctx),
            f"{im.name}.c": env.get_template("model_fast.c.j2").render(**ctx)}
