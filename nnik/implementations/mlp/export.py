"""C generation: render the integer model into NAME.h / NAME.c (C99, no float, no malloc)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik.implementations.mlp import tanh as activations
from nnik.emit.c_text import c_comment_safe
from nnik.implementations.mlp import fastc
from nnik.implementations.mlp import kernel as kern
from nnik.emit.templating import environment
from nnik.errors import NnikError
from nnik.implementations.mlp.fixedpoint import ACT_FRAC, IntegerModel

def c_list(values, per_line: int = 10, suffix: str = "") -> str:
    vals = [f"{int(v)}{suffix}" for v in np.asarray(values).ravel()]
    rows = [", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line)]
    return ",\n".join("    " + r for r in rows)


def render_model_c(im: IntegerModel, scenario_source: str, kernel: str | None = None) -> dict[str, str]:
    """{filename: text} for NAME.h and NAME.c.

    kernel: None (the model's own, ``im.kernel``), "portable" or "fast".  The kernel is part
    of the integer model (``quantize(..., kernel=...)``): the fast C needs a model quantised
    for it, and a fast model has no portable-template rendering.
    """
    kernel = im.kernel if kernel is None else kern.check_kernel(kernel)
    if kernel != im.kernel:
        raise NnikError(f"render_model_c: the model was quantised for kernel {im.kernel!r}, not {kernel!r} "
                        f"(quantize(..., kernel={kernel!r}))")
    if kernel == "fast":
        return fastc.render(im, scenario_source)
    o = im.out
    ctx = dict(
        name=im.name, NAME=im.name.upper(), scenario=c_comment_safe(scenario_source), model_hash=im.model_hash(),
        shape=im.shape, n_in=im.shape[0], n_out=im.shape[-1], unit=im.unit, outputs=im.outputs,
        lo=im.inp.lo.tolist(), hi=im.inp.hi.tolist(), mid=im.inp.mid.tolist(),
        K=im.inp.K.tolist(), M=im.inp.M.tolist(), S=im.inp.S.tolist(),
        hidden=im.hidden, widest=max(max(im.shape[1:-1]), im.shape[0]),
        V=o.V, g=o.g, F=o.F, e=ACT_FRAC + o.g - o.F, C=o.C.tolist(), residual=o.residual,
        A1=o.A1.tolist(), A0=o.A0.tolist(), P=o.P.tolist(), G=o.G.tolist(), code_range=o.code_range,
        weight_bits=im.weight_bits,
        wtype="int16_t" if im.weight_bits == 16 else "int8_t",
        rd="NNIK_RD_I16" if im.weight_bits == 16 else "(int8_t)NNIK_RD_U8",
        tanh_c=activations.render_tanh_c(im.tanh_variant, prefix=im.name),
        c_list=c_list,
    )
    env = environment()
    return {f"{im.name}.h": env.get_template("model.h.j2").render(**ctx),
            f"{im.name}.c": env.get_template("model.c.j2").render(**ctx)}


