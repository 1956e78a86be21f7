"""What every family's C shares: the header, int32 literals and comment-safe text."""

from __future__ import annotations

import numpy as np

from nnik.emit.c_text import c_comment_safe
from nnik.errors import NnikError
from nnik.emit.templating import environment


def i32(v: int) -> str:
    """An int32 constant as C that is correct where int is 16 bits."""
    v = int(v)
    if not -(2**31) <= v < 2**31:
        raise NnikError(f"constant {v} does not fit int32")
    if v == -(2**31):
        return "((int32_t)(-2147483647L - 1L))"
    return f"((int32_t){v}L)"


def comment_safe(text: str) -> str:
    """User text for a C comment (see :func:`nnik.emit.c_text.c_comment_safe`)."""
    return c_comment_safe(text)


def c_list(values, per_line: int = 12, indent: str = "    ") -> str:
    vals = [str(int(v)) for v in np.asarray(values).ravel()]
    rows = [", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line)]
    return (",\n" + indent).join(rows)


def render_header(impl, accuracy: str = "see metrics.json") -> str:
    """NAME.h for any family; the model hash is that of the .c (the header quotes it)."""
    p = impl.problem
    unit_um = f"{p.unit_um:g}"
    return environment().get_template("ik.h.j2").render(
        name=p.name, NAME=p.name.upper(), scenario_name=comment_safe(p.scn.name), family=impl.family,
        describe=comment_safe(impl.describe()), model_hash=impl.source_hash(), outputs=p.outputs, unit=p.unit,
        code_range=p.code_range, unit_um=unit_um, lo=[int(v) for v in p.lo], hi=[int(v) for v in p.hi],
        accuracy=comment_safe(accuracy),
        truth=comment_safe(p.reference.describe(p.unit) if p.reference is not None else "the exact IK"))
