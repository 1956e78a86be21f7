"""The known cost of the portable C's int32 shifts by constants, from the shift microbenchmark."""

from __future__ import annotations

import numpy as np

MAX_SHIFT = 31
SHIFTS = tuple(range(1, MAX_SHIFT + 1))
# the microbenchmark's programs: shift kinds measured together (a PIC18's flash holds one group)
SHIFT_GROUPS = (("rs", "rn", "as", "sl"), ("rsc", "rnc", "asc"))


def shift_bench_c(group: int) -> tuple[str, str]:
    """(name, C source) of the shift microbenchmark program of one group."""
    from nnik.emit.templating import environment

    name = f"nnik_shiftbench{group}"
    return name, environment().get_template("shift_bench.c.j2").render(name=name, shifts=list(SHIFTS),
                                                                        kinds=SHIFT_GROUPS[group])


def _shift_terms(im, style: str = "plain") -> list[tuple[str, str, int, int, int]]:
    """(place, table, amount, executions per call, code sites) of every int32 shift by a
    constant the C performs; style: how the template writes them (portable_shift_style)."""
    c = "c" if style == "chain8" else ""
    o = im.out
    n_out = int(np.asarray(o.V).shape[0])
    terms = []
    for j, (K, S) in enumerate(zip(np.asarray(im.inp.K).tolist(), np.asarray(im.inp.S).tolist())):
        if K > 0:
            terms.append(("input", "rn", int(K), 1, 1))
        if S > 0:
            terms.append(("input", "rn" + c, int(S), 1, 1))
    for L in im.hidden:
        terms.append(("hidden", "rs" + c, int(L.sh), int(np.asarray(L.W).shape[0]), 1))
    e = 15 + int(o.g) - int(o.F)
    if e > 0:
        terms.append(("output", "rs" + c, e, n_out, n_out))
    elif e < 0:
        terms.append(("output", "sl", -e, n_out, n_out))
    if int(o.F) > 0:
        terms.append(("output", "rs" + c, int(o.F), n_out, n_out))
    if o.residual:
        P, G = np.asarray(o.P), np.asarray(o.G)
        for k in range(P.shape[0]):
            for j in range(P.shape[1]):
                if P[k, j] > 0:
                    terms.append(("affine", "as" + c, int(P[k, j]), 1, 1))
                if G[k, j] - P[k, j] > 0:
                    terms.append(("affine", "as" + c, int(G[k, j] - P[k, j]), 1, 1))
    return terms


def shift_offset(im, tables: dict, what: str = "cycles") -> tuple[float, dict]:
    """Known cost of the model's shifts from the microbenchmark tables; (total, per place).
    Cycles count every execution, bytes every code site."""
    per: dict[str, float] = {}
    for place, tab, n, execs, sites in _shift_terms(im, tables.get("style", "plain")):
        if tab not in tables[what]:
            tab = tab.rstrip("c") if tab != "asc" else "as"
        if n > MAX_SHIFT:
            continue
        val = float(tables[what][tab][n]) * (execs if what == "cycles" else sites)
        per[place] = per.get(place, 0.0) + val
    return float(sum(per.values())), per
